// Compiles the shared NPT_HD math for the device. Kernels here are filled in as the shared modules land.
#include "core/rng.h"
#include "core/sampling.h"
#include "core/vec.h"
