#include "render/gpu/optix_renderer.h"

#include <cuda_runtime.h>
#include <optix.h>
#include <optix_stubs.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <string>
#include <utility>

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

std::shared_ptr<void> OptixRenderer::pin(Image& image) {
    float* data = image.pixels.data();
    if (image.pixels.empty() ||
        cudaHostRegister(data, image.pixels.size() * sizeof(float), cudaHostRegisterDefault) != cudaSuccess) {
        cudaGetLastError();  // clear it: the image works without
        spdlog::debug("render: an image could not be page-locked; its downloads are slower");
        return nullptr;
    }
    return std::shared_ptr<void>(data, [](void* p) { cudaHostUnregister(p); });
}

// render_frame's image, page-locked so that the download runs at the bus's speed (a 1080p frame is 25 MB: from
// pageable memory, staged by the driver, it took longer than the NeRF pass's tail). Where the system will not
// lock the pages the image stays pageable: slower, not wrong.
struct OptixRenderer::PinnedImage {
    Image image;
    std::shared_ptr<void> pinned;  // declared after the image: unregistered before its storage is freed
    PinnedImage(int w, int h, int channels) : image(w, h, channels), pinned(pin(image)) {}
    PinnedImage(const PinnedImage&) = delete;
    PinnedImage& operator=(const PinnedImage&) = delete;
};

// Grids through hardware-filtered textures (2x faster on cornell_volume, the same image within noise;
// docs/benchmarks.md) unless NERFPT_OPTIX_GRID_TEXTURES=0, a benchmark knob: the exact eight-voxel lookup.
static bool use_grid_textures() {
    const char* v = std::getenv("NERFPT_OPTIX_GRID_TEXTURES");
    return !(v && std::string(v) == "0");
}

// Scenes with NeRF models are traced in the wavefront form (wavefront.h: the network evaluated in batches on
// tensor cores) unless NERFPT_OPTIX_WAVEFRONT=0, a benchmark knob: every sample evaluated by its own thread.
// Relit NeRFs (media/relit_free_flight.h) included: the NeRF pass samples their free flights and shadow rays'
// transmittance, and the launches shade the events (relit_scatter); segments the pass cannot take (volumes
// overlapping, a network the fp16 kernels do not support) are integrated inline, free flight included.
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
        : scene(scene), width(w), height(h), data(scene, w, h), dev(data.view(), use_grid_textures()),
          accel(ctx.get(), dev, stream.s),
          programs(ctx.get(), accel.input_meshes()) {
        if (data.view().volumes.size > 0 && use_wavefront()) {
            const size_t pixels = size_t(w) * size_t(h);
            wavefront = std::make_unique<WavefrontLoop>(data.view().volumes, dev.view().volumes,
                                                        pixels * slots_for(pixels, k_max_slots), stream.s);
            if (!wavefront->useful()) wavefront.reset();
        }
    }
    const scene::Scene& scene;
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
    DeviceBuffer<float> rgb;  // the resolved image, 3 or 4 floats a pixel
    DeviceBuffer<float4> first_hit;  // the AOVs' planes (optix_launch.h), when asked for
    DeviceBuffer<float> aov_out;     // the resolved AOVs: albedo, normal (3 floats a pixel), depth (1)
    DeviceBuffer<unsigned long long> dropped{1};
    DeviceBuffer<LaunchParams> params{1};
    std::unique_ptr<PinnedImage> frame;  // render_frame's, made by its first call

    // Renders into the device image (rgb); with albedo and normal, also writes the denoiser's guides there;
    // with `aovs`, the AOVs of options.aovs into aov_out.
    void trace(const render::RenderOptions& options, const render::ProgressFn& progress, float4* albedo,
               float4* normal, bool aovs);
    // Downloads the device image into `image` (its channels: the render's) and the AOVs asked for into *aovs
    // (null: none), and warns about dropped samples.
    void download(Image& image, render::AovImages* aovs);
};

OptixRenderer::OptixRenderer(const scene::Scene& scene, int width, int height) {
    const std::string device = nerf::cuda::require_cuda_device();
    spdlog::debug("OptiX on {}", device);
    m = std::make_unique<State>(scene, width, height);
}

OptixRenderer::~OptixRenderer() = default;

void OptixRenderer::update(const scene::PoseChanges& changes) {
    if (!changes.any()) return;
    m->data.update(m->scene, changes);
    m->dev.update(m->data.view(), changes.meshes, changes.volumes);
    // A rebuild, not a refit: the GAS is compacted (refitting needs OPTIX_BUILD_FLAG_ALLOW_UPDATE and the
    // uncompacted size), and a rigid mesh that turns makes a refitted BVH's boxes loose.
    if (!changes.meshes.empty()) m->accel = OptixAccel(m->ctx.get(), m->dev, m->stream.s);
}

Image OptixRenderer::render(const render::RenderOptions& options, const render::ProgressFn& progress,
                            Image* denoised, render::AovImages* aovs) {
    Image image;
    render_to(options, image, progress, denoised, aovs);
    return image;
}

void OptixRenderer::render_into(const render::RenderOptions& options, Image& out, const render::ProgressFn& progress,
                                render::AovImages* aovs) {
    render_to(options, out, progress, nullptr, aovs);
}

void OptixRenderer::render_to(const render::RenderOptions& options, Image& out, const render::ProgressFn& progress,
                              Image* denoised, render::AovImages* aovs) {
    const size_t pixels = size_t(m->width) * size_t(m->height);
    std::unique_ptr<OptixDenoiserPass> denoiser;
    DeviceBuffer<float4> albedo, normal;  // the denoiser's guides
    if (denoised) {
        denoiser = std::make_unique<OptixDenoiserPass>(m->ctx.get(), m->stream.s, m->width, m->height);
        albedo.allocate(pixels, "the denoiser's guides", "--res");
        normal.allocate(pixels, "the denoiser's guides", "--res");
    }
    const bool want_aovs = aovs && options.aovs != 0;
    m->trace(options, progress, albedo.data(), normal.data(), want_aovs);
    const int channels = options.transparent ? 4 : 3;
    if (out.width != m->width || out.height != m->height || out.channels != channels)
        out = Image(m->width, m->height, channels);  // else its storage is reused
    if (want_aovs) *aovs = render::make_aov_images(m->width, m->height, options.aovs);
    m->download(out, want_aovs ? aovs : nullptr);
    if (denoiser) *denoised = denoiser->run(out, albedo.data(), normal.data());
}

const Image& OptixRenderer::render_frame(const render::RenderOptions& options) {
    const int channels = options.transparent ? 4 : 3;
    if (!m->frame || m->frame->image.channels != channels)
        m->frame = std::make_unique<PinnedImage>(m->width, m->height, channels);
    m->trace(options, {}, nullptr, nullptr, false);
    m->download(m->frame->image, nullptr);
    return m->frame->image;
}

void OptixRenderer::State::download(Image& image, render::AovImages* aovs) {
    cudaStream_t s = stream.s;
    const size_t pixels = size_t(width) * size_t(height);
    if (image.pixels.size() != rgb.size()) throw Error("OptixRenderer: the image has the wrong number of channels");
    cuda_check(cudaMemcpyAsync(image.pixels.data(), rgb.data(), rgb.bytes(), cudaMemcpyDeviceToHost, s),
               "downloading the image");
    if (aovs) {
        const std::pair<Image*, size_t> layers[] = {
            {&aovs->albedo, 0}, {&aovs->normal, 3 * pixels}, {&aovs->depth, 6 * pixels}};
        for (const auto& [layer, offset] : layers)
            if (!layer->pixels.empty())
                cuda_check(cudaMemcpyAsync(layer->pixels.data(), aov_out.data() + offset,
                                           layer->pixels.size() * sizeof(float), cudaMemcpyDeviceToHost, s),
                           "downloading the AOVs");
    }
    unsigned long long bad = 0;
    cuda_check(cudaMemcpyAsync(&bad, dropped.data(), sizeof bad, cudaMemcpyDeviceToHost, s),
               "cudaMemcpyAsync");
    cuda_check(cudaStreamSynchronize(s), "rendering with OptiX");
    if (bad > 0) spdlog::warn("render: {} samples were NaN or infinite and were dropped", bad);
}

void OptixRenderer::State::trace(const render::RenderOptions& options, const render::ProgressFn& progress,
                                 float4* albedo, float4* normal, bool aovs) {
    if (options.width != width || options.height != height)
        throw Error("OptixRenderer: built for " + std::to_string(width) + "x" + std::to_string(height) +
                    ", asked for " + std::to_string(options.width) + "x" + std::to_string(options.height));
    const uint32_t spp = uint32_t(options.spp);
    cudaStream_t s = stream.s;
    const bool guides = albedo != nullptr;

    const size_t pixels = size_t(width) * size_t(height);
    // Sample slots: a launch of width x height x slots threads, slot z tracing samples z, z + slots, ... of its
    // pixel into its own plane of sums; the planes are added in a fixed order, so a seed gives one image.
    const uint32_t slots = slots_for(pixels, spp);
    if (accum.size() < pixels * slots) accum.allocate(pixels * slots, "the image", "--res");
    cuda_check(cudaMemsetAsync(accum.data(), 0, pixels * slots * sizeof(float4), s), "cudaMemsetAsync");
    const int channels = options.transparent ? 4 : 3;
    if (rgb.size() != size_t(channels) * pixels) rgb.allocate(size_t(channels) * pixels, "the image", "--res");
    if (aovs) {
        if (first_hit.size() < 2 * pixels * slots) first_hit.allocate(2 * pixels * slots, "the AOVs", "--res");
        cuda_check(cudaMemsetAsync(first_hit.data(), 0, 2 * pixels * slots * sizeof(float4), s), "cudaMemsetAsync");
        if (aov_out.size() < 7 * pixels) aov_out.allocate(7 * pixels, "the AOVs", "--res");
    }
    dropped.zero_async(s);

    LaunchParams p;
    p.scene = dev.view();
    p.handle = accel.handle();
    p.accum = accum.data();
    p.dropped = dropped.data();
    p.width = width;
    p.height = height;
    p.slots = slots;
    p.seed = options.seed;
    p.albedo = albedo;
    p.normal = normal;
    p.path.max_depth = options.max_depth;
    p.path.transparent_background = options.transparent;
    p.first_hit = aovs ? first_hit.data() : nullptr;

    const uint64_t total = uint64_t(pixels) * spp;
    uint32_t done = 0, batch = slots;  // the first launch: one sample per slot
    if (wavefront) {
        if (guides) {
            // The guides only: the per-thread program with no samples writes them (sample_begin 0, slot 0).
            p.sample_begin = p.sample_count = 0;
            cuda_check(cudaMemcpyAsync(params.data(), &p, sizeof p, cudaMemcpyHostToDevice, s), "cudaMemcpyAsync");
            optix_check(optixLaunch(programs.pipeline(), s, CUdeviceptr(params.data()), sizeof(LaunchParams),
                                    &programs.sbt(), unsigned(width), unsigned(height), 1),
                        "optixLaunch");
        }
        for (; done < spp; done += batch) {
            batch = std::min(slots, spp - done);
            p.sample_begin = done;
            wavefront->run_wave(p, batch, programs, params.data());
            if (progress) progress(uint64_t(pixels) * (done + batch), total);
        }
    }
    while (done < spp) {
        p.sample_begin = done;
        p.sample_count = std::min(batch, spp - done);
        cuda_check(cudaMemcpyAsync(params.data(), &p, sizeof p, cudaMemcpyHostToDevice, s), "cudaMemcpyAsync");
        const auto t0 = std::chrono::steady_clock::now();
        optix_check(optixLaunch(programs.pipeline(), s, CUdeviceptr(params.data()), sizeof(LaunchParams),
                                &programs.sbt(), unsigned(width), unsigned(height),
                                std::min(slots, p.sample_count)),
                    "optixLaunch");
        cuda_check(cudaStreamSynchronize(s), "rendering with OptiX");
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        done += p.sample_count;
        if (progress) progress(uint64_t(pixels) * done, total);
        // Size the next launch from this one: about k_launch_target_seconds each, whole rounds of slots.
        const double per_sample = seconds / double(p.sample_count);
        const double next = std::clamp(k_launch_target_seconds / std::max(per_sample, 1e-7), 1.0, 4096.0);
        batch = std::max(slots, uint32_t(next) / slots * slots);
    }

    resolve_image(accum.data(), slots, pixels, 1.0f / float(spp), channels, rgb.data(), s);
    if (aovs)
        resolve_first_hits(first_hit.data(), slots, pixels, options.aovs & render::k_aov_albedo ? aov_out.data() : nullptr,
                           options.aovs & render::k_aov_normal ? aov_out.data() + 3 * pixels : nullptr,
                           options.aovs & render::k_aov_depth ? aov_out.data() + 6 * pixels : nullptr, s);
}

Image render_optix(const scene::Scene& scene, const render::RenderOptions& options,
                   const render::ProgressFn& progress, Image* denoised, render::AovImages* aovs) {
    OptixRenderer renderer(scene, options.width, options.height);
    return renderer.render(options, progress, denoised, aovs);
}

}  // namespace npt::gpu
