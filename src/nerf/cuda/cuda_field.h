// The NeRF field at arbitrary points on the GPU, for bakes and for tests against the CPU: sigma and colour
// from the fused fp16 tensor-core kernels, or from the fp32 per-point code the CPU uses (NerfFieldView).
#pragma once

#include <vector>

#include "core/vec.h"
#include "nerf/cuda/cuda_renderer.h"
#include "nerf/nerf_model.h"

namespace npt::nerf::cuda {

// positions in model space; dirs unit length (same count), or empty for density only (rgb then untouched).
void evaluate_field(const NerfModel& model, const std::vector<Vec3>& positions, const std::vector<Vec3>& dirs,
                    Precision precision, std::vector<float>& sigma, std::vector<Rgb>& rgb);

}  // namespace npt::nerf::cuda
