// OptiX's AI denoiser (the driver's HDR model) with albedo and normal guide layers, for `nerfpt render
// --denoise`: a clean image from few samples, beside the noisy one the user keeps.
#pragma once

#include <cuda_runtime.h>
#include <optix_types.h>

#include "core/image.h"

namespace npt::gpu {

// noisy: linear RGB (3 channels); albedo and normal: device guides of the same size (float4 per pixel).
Image optix_denoise(OptixDeviceContext ctx, cudaStream_t stream, const Image& noisy, const float4* albedo,
                    const float4* normal);

}  // namespace npt::gpu
