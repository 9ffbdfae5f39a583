// Whether a CUDA GPU can be used here, and a one-line description of it for logs and benchmarks.
#pragma once

#include <string>

namespace npt::nerf::cuda {

// True when device 0 can run our kernels (compute capability 7.0 or newer: tensor cores); otherwise `why`
// says what is missing (no driver, no device, an old driver, an old GPU).
bool cuda_device_usable(std::string* why);

// Selects device 0 and returns "NVIDIA H200 (sm_90, 132 SMs, 140.4 GiB, driver 13.0)"; throws npt::Error with
// the reason when it cannot be used.
std::string require_cuda_device();

}  // namespace npt::nerf::cuda
