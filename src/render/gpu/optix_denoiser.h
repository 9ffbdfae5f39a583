// OptiX's AI denoiser (the driver's HDR model) with albedo and normal guide layers, for `nerfpt render
// --denoise`: a clean image from few samples, beside the noisy one the user keeps. Created before the render
// starts, so that a driver without the denoiser fails the command at once, not after the render.
#pragma once

#include <cuda_runtime.h>
#include <optix_types.h>

#include "core/cuda/device_buffer.h"
#include "core/image.h"

namespace npt::gpu {

class OptixDenoiserPass {
  public:
    // Throws npt::Error (one line) when the driver cannot create the denoiser, e.g. without its weights file.
    OptixDenoiserPass(OptixDeviceContext ctx, cudaStream_t stream, int width, int height);
    ~OptixDenoiserPass();
    OptixDenoiserPass(const OptixDenoiserPass&) = delete;
    OptixDenoiserPass& operator=(const OptixDenoiserPass&) = delete;

    // noisy: linear RGB (3 channels) or premultiplied RGBA (4: the alpha is kept as it is); albedo and normal:
    // device guides of the same size (float4 per pixel). The result has noisy's channels.
    Image run(const Image& noisy, const float4* albedo, const float4* normal);

  private:
    OptixDenoiser m_denoiser = nullptr;
    cudaStream_t m_stream;
    unsigned m_width, m_height;
    DeviceBuffer<unsigned char> m_state, m_scratch;
};

}  // namespace npt::gpu
