#include "render/gpu/optix_denoiser.h"

#include <optix.h>
#include <optix_stubs.h>

#include <vector>

#include "core/cuda/device_buffer.h"
#include "render/gpu/optix_context.h"

namespace npt::gpu {

Image optix_denoise(OptixDeviceContext ctx, cudaStream_t stream, const Image& noisy, const float4* albedo,
                    const float4* normal) {
    const unsigned w = unsigned(noisy.width), h = unsigned(noisy.height);
    const size_t n = size_t(w) * size_t(h);
    std::vector<float4> in(n);
    for (size_t i = 0; i < n; ++i)
        in[i] = make_float4(noisy.pixels[3 * i], noisy.pixels[3 * i + 1], noisy.pixels[3 * i + 2], 1.0f);
    DeviceBuffer<float4> input(in), output(n, "the denoised image", "--res");

    OptixDenoiserOptions options{};
    options.guideAlbedo = 1;
    options.guideNormal = 1;
    options.denoiseAlpha = OPTIX_DENOISER_ALPHA_MODE_COPY;
    OptixDenoiser denoiser = nullptr;
    optix_check(optixDenoiserCreate(ctx, OPTIX_DENOISER_MODEL_KIND_HDR, &options, &denoiser), "optixDenoiserCreate");
    struct Guard {
        OptixDenoiser d;
        ~Guard() { optixDenoiserDestroy(d); }
    } guard{denoiser};
    OptixDenoiserSizes sizes{};
    optix_check(optixDenoiserComputeMemoryResources(denoiser, w, h, &sizes), "optixDenoiserComputeMemoryResources");
    DeviceBuffer<unsigned char> state(sizes.stateSizeInBytes, "the denoiser", "--res");
    DeviceBuffer<unsigned char> scratch(sizes.withoutOverlapScratchSizeInBytes, "the denoiser", "--res");
    optix_check(optixDenoiserSetup(denoiser, stream, w, h, CUdeviceptr(state.data()), state.bytes(),
                                   CUdeviceptr(scratch.data()), scratch.bytes()),
                "optixDenoiserSetup");

    auto image = [&](const float4* p) {
        OptixImage2D i{};
        i.data = CUdeviceptr(p);
        i.width = w;
        i.height = h;
        i.rowStrideInBytes = w * unsigned(sizeof(float4));
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
    optix_check(optixDenoiserInvoke(denoiser, stream, &params, CUdeviceptr(state.data()), state.bytes(), &guides,
                                    &layer, 1, 0, 0, CUdeviceptr(scratch.data()), scratch.bytes()),
                "optixDenoiserInvoke");
    cuda_check(cudaStreamSynchronize(stream), "denoising");

    const std::vector<float4> out = output.download();
    Image result(noisy.width, noisy.height, 3);
    for (size_t i = 0; i < n; ++i) {
        result.pixels[3 * i] = out[i].x;
        result.pixels[3 * i + 1] = out[i].y;
        result.pixels[3 * i + 2] = out[i].z;
    }
    return result;
}

}  // namespace npt::gpu
