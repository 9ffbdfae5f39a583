#include "render/gpu/optix_renderer.h"

#include <cuda_runtime.h>
#include <optix.h>
#include <optix_stubs.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <string>

#include "core/cuda/device_buffer.h"
#include "core/error.h"
#include "nerf/cuda/cuda_device.h"
#include "render/gpu/device_scene.h"
#include "render/gpu/image_resolve.h"
#include "render/gpu/optix_accel.h"
#include "render/gpu/optix_context.h"
#include "render/gpu/optix_denoiser.h"
#include "render/gpu/optix_launch.h"
#include "render/gpu/optix_pipeline.h"
#include "render/gpu/optix_wavefront.h"
#include "render/scene_data.h"

namespace npt::gpu {

namespace {
// A launch aims at this long, so that progress moves and Ctrl-C is answered quickly.
constexpr double k_launch_target_seconds = 0.1;
// Threads a launch should have to fill the GPU (132 SMs x 2048 resident threads is 270 k; more hides the tails
// of long paths). A small image gets that many by tracing several of a pixel's samples side by side.
constexpr size_t k_threads_per_launch = size_t(1) << 21;
constexpr uint32_t k_max_slots = 64;

struct StreamOwner {
    cudaStream_t s = nullptr;
    StreamOwner() { cuda_check(cudaStreamCreate(&s), "cudaStreamCreate"); }
    ~StreamOwner() { cudaStreamDestroy(s); }
};
}  // namespace

// Grids through hardware-filtered textures (2x faster on cornell_volume, the same image within noise;
// docs/benchmarks.md) unless NERFPT_OPTIX_GRID_TEXTURES=0, a benchmark knob: the exact eight-voxel lookup.
static bool use_grid_textures() {
    const char* v = std::getenv("NERFPT_OPTIX_GRID_TEXTURES");
    return !(v && std::string(v) == "0");
}

// Scenes with NeRF models are traced in the wavefront form (wavefront.h: the network evaluated in batches on
// tensor cores) unless NERFPT_OPTIX_WAVEFRONT=0, a benchmark knob: every sample evaluated by its own thread.
static bool use_wavefront() {
    const char* v = std::getenv("NERFPT_OPTIX_WAVEFRONT");
    return !(v && std::string(v) == "0");
}

// Sample slots for an image of `pixels`: enough threads per launch to fill the GPU, at most spp.
static uint32_t slots_for(size_t pixels, uint32_t spp) {
    return uint32_t(std::clamp<size_t>((k_threads_per_launch + pixels - 1) / pixels, 1,
                                       std::min<size_t>(k_max_slots, spp)));
}

struct OptixRenderer::State {
    State(const scene::Scene& scene, int w, int h)
        : width(w), height(h), data(scene, w, h), dev(data.view(), use_grid_textures()),
          accel(ctx.get(), dev, stream.s),
          programs(ctx.get(), accel.input_meshes()) {
        if (use_wavefront() && data.view().volumes.size > 0) {
            const size_t pixels = size_t(w) * size_t(h);
            wavefront = std::make_unique<WavefrontLoop>(data.view().volumes, dev.view().volumes,
                                                        pixels * slots_for(pixels, k_max_slots), stream.s);
            if (!wavefront->useful()) wavefront.reset();
        }
    }
    int width, height;
    render::SceneData data;
    DeviceScene dev;
    OptixContext ctx;
    StreamOwner stream;
    OptixAccel accel;
    OptixPrograms programs;
    std::unique_ptr<WavefrontLoop> wavefront;  // null: the per-thread form
    // Kept from frame to frame (an allocation and a free cost more than a 1080p frame of the baked demo).
    DeviceBuffer<float4> accum;
    DeviceBuffer<float> rgb;
    DeviceBuffer<unsigned long long> dropped{1};
    DeviceBuffer<LaunchParams> params{1};
};

OptixRenderer::OptixRenderer(const scene::Scene& scene, int width, int height) {
    const std::string device = nerf::cuda::require_cuda_device();
    spdlog::debug("OptiX on {}", device);
    m = std::make_unique<State>(scene, width, height);
}

OptixRenderer::~OptixRenderer() = default;

Image OptixRenderer::render(const render::RenderOptions& options, const render::ProgressFn& progress,
                            Image* denoised) {
    const int width = m->width, height = m->height;
    if (options.width != width || options.height != height)
        throw Error("OptixRenderer: built for " + std::to_string(width) + "x" + std::to_string(height) +
                    ", asked for " + std::to_string(options.width) + "x" + std::to_string(options.height));
    const uint32_t spp = uint32_t(options.spp);
    cudaStream_t stream = m->stream.s;
    std::unique_ptr<OptixDenoiserPass> denoiser;
    if (denoised) denoiser = std::make_unique<OptixDenoiserPass>(m->ctx.get(), stream, width, height);

    const size_t pixels = size_t(width) * size_t(height);
    // Sample slots: a launch of width x height x slots threads, slot z tracing samples z, z + slots, ... of its
    // pixel into its own plane of sums; the planes are added in a fixed order, so a seed gives one image.
    const uint32_t slots = slots_for(pixels, spp);
    DeviceBuffer<float4>& accum = m->accum;
    if (accum.size() < pixels * slots) accum.allocate(pixels * slots, "the image", "--res");
    cuda_check(cudaMemsetAsync(accum.data(), 0, pixels * slots * sizeof(float4), stream), "cudaMemsetAsync");
    if (m->rgb.size() != 3 * pixels) m->rgb.allocate(3 * pixels, "the image", "--res");
    const DeviceBuffer<unsigned long long>& dropped = m->dropped;
    dropped.zero_async(stream);
    const DeviceBuffer<LaunchParams>& params = m->params;
    DeviceBuffer<float4> albedo, normal;  // the denoiser's guides
    if (denoised) {
        albedo.allocate(pixels, "the denoiser's guides", "--res");
        normal.allocate(pixels, "the denoiser's guides", "--res");
    }

    LaunchParams p;
    p.scene = m->dev.view();
    p.handle = m->accel.handle();
    p.accum = accum.data();
    p.dropped = dropped.data();
    p.width = width;
    p.height = height;
    p.slots = slots;
    p.seed = options.seed;
    p.albedo = albedo.data();
    p.normal = normal.data();
    p.path.max_depth = options.max_depth;

    const uint64_t total = uint64_t(pixels) * spp;
    uint32_t done = 0, batch = slots;  // the first launch: one sample per slot
    if (m->wavefront) {
        if (denoised) {
            // The guides only: the per-thread program with no samples writes them (sample_begin 0, slot 0).
            p.sample_begin = p.sample_count = 0;
            cuda_check(cudaMemcpyAsync(params.data(), &p, sizeof p, cudaMemcpyHostToDevice, stream), "cudaMemcpyAsync");
            optix_check(optixLaunch(m->programs.pipeline(), stream, CUdeviceptr(params.data()), sizeof(LaunchParams),
                                    &m->programs.sbt(), unsigned(width), unsigned(height), 1),
                        "optixLaunch");
        }
        for (; done < spp; done += batch) {
            batch = std::min(slots, spp - done);
            p.sample_begin = done;
            m->wavefront->run_wave(p, batch, m->programs, params.data());
            if (progress) progress(uint64_t(pixels) * (done + batch), total);
        }
    }
    while (done < spp) {
        p.sample_begin = done;
        p.sample_count = std::min(batch, spp - done);
        cuda_check(cudaMemcpyAsync(params.data(), &p, sizeof p, cudaMemcpyHostToDevice, stream), "cudaMemcpyAsync");
        const auto t0 = std::chrono::steady_clock::now();
        optix_check(optixLaunch(m->programs.pipeline(), stream, CUdeviceptr(params.data()), sizeof(LaunchParams),
                                &m->programs.sbt(), unsigned(width), unsigned(height),
                                std::min(slots, p.sample_count)),
                    "optixLaunch");
        cuda_check(cudaStreamSynchronize(stream), "rendering with OptiX");
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        done += p.sample_count;
        if (progress) progress(uint64_t(pixels) * done, total);
        // Size the next launch from this one: about k_launch_target_seconds each, whole rounds of slots.
        const double per_sample = seconds / double(p.sample_count);
        const double next = std::clamp(k_launch_target_seconds / std::max(per_sample, 1e-7), 1.0, 4096.0);
        batch = std::max(slots, uint32_t(next) / slots * slots);
    }

    resolve_image(accum.data(), slots, pixels, 1.0f / float(spp), m->rgb.data(), stream);
    Image image(width, height, 3);
    cuda_check(cudaMemcpyAsync(image.pixels.data(), m->rgb.data(), m->rgb.bytes(), cudaMemcpyDeviceToHost, stream),
               "downloading the image");
    unsigned long long bad = 0;
    cuda_check(cudaMemcpyAsync(&bad, dropped.data(), sizeof bad, cudaMemcpyDeviceToHost, stream), "cudaMemcpyAsync");
    cuda_check(cudaStreamSynchronize(stream), "rendering with OptiX");
    if (bad > 0) spdlog::warn("render: {} samples were NaN or infinite and were dropped", bad);
    if (denoiser) *denoised = denoiser->run(image, albedo.data(), normal.data());
    return image;
}

Image render_optix(const scene::Scene& scene, const render::RenderOptions& options,
                   const render::ProgressFn& progress, Image* denoised) {
    OptixRenderer renderer(scene, options.width, options.height);
    return renderer.render(options, progress, denoised);
}

}  // namespace npt::gpu
