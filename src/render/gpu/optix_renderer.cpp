#include "render/gpu/optix_renderer.h"

#include <cuda_runtime.h>
#include <optix.h>
#include <optix_stubs.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>

#include "core/cuda/device_buffer.h"
#include "nerf/cuda/cuda_device.h"
#include "render/gpu/device_scene.h"
#include "render/gpu/optix_accel.h"
#include "render/gpu/optix_context.h"
#include "render/gpu/optix_denoiser.h"
#include "render/gpu/optix_launch.h"
#include "render/gpu/optix_pipeline.h"
#include "render/scene_data.h"

namespace npt::gpu {

namespace {
// A launch aims at this long, so that progress moves and Ctrl-C is answered quickly.
constexpr double k_launch_target_seconds = 0.1;
}  // namespace

Image render_optix(const scene::Scene& scene, const render::RenderOptions& options,
                   const render::ProgressFn& progress, Image* denoised) {
    const std::string device = nerf::cuda::require_cuda_device();
    spdlog::debug("OptiX on {}", device);
    const int width = options.width, height = options.height, spp = options.spp;
    const render::SceneData data(scene, width, height);
    const DeviceScene dev(data.view());
    const OptixContext ctx;
    cudaStream_t stream = nullptr;
    cuda_check(cudaStreamCreate(&stream), "cudaStreamCreate");
    struct StreamGuard {
        cudaStream_t s;
        ~StreamGuard() { cudaStreamDestroy(s); }
    } guard{stream};
    const OptixAccel accel(ctx.get(), dev, stream);
    const OptixPrograms programs(ctx.get());

    const size_t pixels = size_t(width) * size_t(height);
    DeviceBuffer<float4> accum(pixels, "the image", "--res");
    accum.zero_async(stream);
    DeviceBuffer<unsigned long long> dropped(1);
    dropped.zero_async(stream);
    DeviceBuffer<LaunchParams> params(1);
    DeviceBuffer<float4> albedo, normal;  // the denoiser's guides
    if (denoised) {
        albedo.allocate(pixels, "the denoiser's guides", "--res");
        normal.allocate(pixels, "the denoiser's guides", "--res");
    }

    LaunchParams p;
    p.scene = dev.view();
    p.handle = accel.handle();
    p.accum = accum.data();
    p.dropped = dropped.data();
    p.width = width;
    p.height = height;
    p.seed = options.seed;
    p.albedo = albedo.data();
    p.normal = normal.data();
    p.path.max_depth = options.max_depth;

    const uint64_t total = uint64_t(pixels) * uint64_t(spp);
    uint32_t done = 0, batch = 1;
    while (done < uint32_t(spp)) {
        p.sample_begin = done;
        p.sample_count = std::min<uint32_t>(batch, uint32_t(spp) - done);
        cuda_check(cudaMemcpyAsync(params.data(), &p, sizeof p, cudaMemcpyHostToDevice, stream), "cudaMemcpyAsync");
        const auto t0 = std::chrono::steady_clock::now();
        optix_check(optixLaunch(programs.pipeline(), stream, CUdeviceptr(params.data()), sizeof(LaunchParams),
                                &programs.sbt(), unsigned(width), unsigned(height), 1),
                    "optixLaunch");
        cuda_check(cudaStreamSynchronize(stream), "rendering with OptiX");
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        done += p.sample_count;
        if (progress) progress(uint64_t(pixels) * done, total);
        // Size the next launch from this one: about k_launch_target_seconds each.
        const double per_sample = seconds / double(p.sample_count);
        batch = uint32_t(std::clamp(k_launch_target_seconds / std::max(per_sample, 1e-6), 1.0, 1024.0));
    }

    const std::vector<float4> sums = accum.download();
    const unsigned long long bad = dropped.download()[0];
    if (bad > 0) spdlog::warn("render: {} samples were NaN or infinite and were dropped", bad);
    Image image(width, height, 3);
    const float inv = 1.0f / float(spp);
    for (size_t i = 0; i < pixels; ++i) {
        image.pixels[3 * i + 0] = sums[i].x * inv;
        image.pixels[3 * i + 1] = sums[i].y * inv;
        image.pixels[3 * i + 2] = sums[i].z * inv;
    }
    if (denoised) *denoised = optix_denoise(ctx.get(), stream, image, albedo.data(), normal.data());
    return image;
}

}  // namespace npt::gpu
