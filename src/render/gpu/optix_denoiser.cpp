#include "render/gpu/optix_denoiser.h"

#include <optix.h>
#include <optix_stubs.h>

#include <string>
#include <vector>

#include "core/error.h"
#include "render/gpu/optix_context.h"

namespace npt::gpu {

OptixDenoiserPass::OptixDenoiserPass(OptixDeviceContext ctx, cudaStream_t stream, int width, int height)
    : m_stream(stream), m_width(unsigned(width)), m_height(unsigned(height)) {
    OptixDenoiserOptions options{};
    options.guideAlbedo = 1;
    options.guideNormal = 1;
    options.denoiseAlpha = OPTIX_DENOISER_ALPHA_MODE_COPY;
    const OptixResult r = optixDenoiserCreate(ctx, OPTIX_DENOISER_MODEL_KIND_HDR, &options, &m_denoiser);
    // The driver loads the network's weights from a file of its own package (nvoptix.bin); a driver installed
    // without it (seen on a headless compute install) fails here with an internal error.
    if (r != OPTIX_SUCCESS)
        throw Error(std::string("--denoise: the NVIDIA driver could not create the OptiX denoiser (") +
                    optixGetErrorName(r) +
                    "; a driver installed without its denoiser weights, nvoptix.bin, does this): render without "
                    "--denoise or install the full driver");
    OptixDenoiserSizes sizes{};
    optix_check(optixDenoiserComputeMemoryResources(m_denoiser, m_width, m_height, &sizes),
                "optixDenoiserComputeMemoryResources");
    m_state.allocate(sizes.stateSizeInBytes, "the denoiser", "--res");
    m_scratch.allocate(sizes.withoutOverlapScratchSizeInBytes, "the denoiser", "--res");
    optix_check(optixDenoiserSetup(m_denoiser, stream, m_width, m_height, CUdeviceptr(m_state.data()),
                                   m_state.bytes(), CUdeviceptr(m_scratch.data()), m_scratch.bytes()),
                "optixDenoiserSetup");
}

OptixDenoiserPass::~OptixDenoiserPass() {
    if (m_denoiser) optixDenoiserDestroy(m_denoiser);
}

Image OptixDenoiserPass::run(const Image& noisy, const float4* albedo, const float4* normal) {
    const size_t n = size_t(m_width) * size_t(m_height);
    const size_t c = size_t(noisy.channels);
    std::vector<float4> in(n);
    for (size_t i = 0; i < n; ++i)
        in[i] = make_float4(noisy.pixels[c * i], noisy.pixels[c * i + 1], noisy.pixels[c * i + 2], 1.0f);
    DeviceBuffer<float4> input(in), output(n, "the denoised image", "--res");

    auto image = [&](const float4* p) {
        OptixImage2D i{};
        i.data = CUdeviceptr(p);
        i.width = m_width;
        i.height = m_height;
        i.rowStrideInBytes = m_width * unsigned(sizeof(float4));
        i.pixelStrideInBytes = unsigned(sizeof(float4));
        i.format = OPTIX_PIXEL_FORMAT_FLOAT4;
        return i;
    };
    OptixDenoiserGuideLayer guides{};
    guides.albedo = image(albedo);
    guides.normal = image(normal);
    OptixDenoiserLayer layer{};
    layer.input = image(input.data());
    layer.output = image(output.data());
    OptixDenoiserParams params{};  // hdrIntensity 0: the denoiser measures the exposure itself
    optix_check(optixDenoiserInvoke(m_denoiser, m_stream, &params, CUdeviceptr(m_state.data()), m_state.bytes(),
                                    &guides, &layer, 1, 0, 0, CUdeviceptr(m_scratch.data()), m_scratch.bytes()),
                "optixDenoiserInvoke");
    cuda_check(cudaStreamSynchronize(m_stream), "denoising");

    const std::vector<float4> out = output.download();
    Image result(noisy.width, noisy.height, noisy.channels);
    for (size_t i = 0; i < n; ++i) {
        result.pixels[c * i] = out[i].x;
        result.pixels[c * i + 1] = out[i].y;
        result.pixels[c * i + 2] = out[i].z;
        if (c == 4) result.pixels[c * i + 3] = noisy.pixels[c * i + 3];
    }
    return result;
}

}  // namespace npt::gpu
