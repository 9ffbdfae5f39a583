#include "render/cpu/cpu_renderer.h"

#include <spdlog/spdlog.h>
#include <tbb/blocked_range2d.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <mutex>

#include "core/error.h"
#include "core/memory.h"
#include "render/camera.h"
#include "render/cpu/embree_scene.h"
#include "render/path_integrator.h"
#include "render/sample_sums.h"
#include "render/scene_data.h"

namespace npt::render::cpu {

namespace {
constexpr int k_tile = 16;
}

CpuFrameRenderer::CpuFrameRenderer(const scene::Scene& scene, int width, int height)
    : m_scene(scene),
      m_data(std::make_unique<SceneData>(scene, width, height)),
      m_embree(std::make_unique<EmbreeScene>(scene)),
      m_width(width),
      m_height(height) {}

CpuFrameRenderer::~CpuFrameRenderer() = default;

void CpuFrameRenderer::update(const scene::PoseChanges& changes) {
    m_embree->update(m_scene, changes);
    m_data->update(m_scene, changes);
}

Image render_cpu(const scene::Scene& scene, const RenderOptions& options, const ProgressFn& progress,
                 AovImages* aovs) {
    return CpuFrameRenderer(scene, options.width, options.height).render(options, progress, aovs);
}

// The tiles of the image over TBB's threads; pixel(x, y, leaf) is called once per pixel with leaf(s), the
// sums of sample s alone (its radiance, or 0 when it was NaN or infinite, and its first hit's record).
template <class PixelFn>
void CpuFrameRenderer::for_each_pixel(const RenderOptions& options, uint64_t samples_per_pixel,
                                      const ProgressFn& progress, const PixelFn& pixel) {
    const int width = options.width, height = options.height;
    if (width != m_width || height != m_height)
        throw Error("render: " + std::to_string(width) + "x" + std::to_string(height) + " asked of a renderer prepared for " +
                    std::to_string(m_width) + "x" + std::to_string(m_height));
    EmbreeTracer tracer(*m_embree);
    const SceneView& sv = m_data->view();
    PathSettings ps;
    ps.max_depth = options.max_depth;
    ps.transparent_background = options.transparent;
    // The camera ray's first hit is recorded only where the film needs it.
    const bool record_first = options.transparent || options.aovs != 0;
    const uint64_t total = uint64_t(width) * uint64_t(height) * samples_per_pixel;
    std::atomic<uint64_t> done{0};
    std::atomic<uint64_t> dropped{0};
    std::mutex progress_mutex;

    auto render_tile = [&](const tbb::blocked_range2d<int>& r) {
        for (int y = r.rows().begin(); y < r.rows().end(); ++y)
            for (int x = r.cols().begin(); x < r.cols().end(); ++x) {
                const auto leaf = [&](uint32_t s) {
                    SobolSampler sampler(options.seed, uint32_t(x), uint32_t(y), s);
                    Ray ray = generate_camera_ray(sv.camera, x, y, sampler.next_2d());
                    FirstHit first;
                    const Rgb l = trace_path(sv, tracer, ray, sampler, ps, record_first ? &first : nullptr);
                    PixelSums v;
                    add_first_hit(v.first, first);  // a dropped sample's coverage still counts
                    if (is_finite(l))
                        v.radiance = l;
                    else
                        dropped.fetch_add(1, std::memory_order_relaxed);
                    return v;
                };
                pixel(x, y, leaf);
            }
        uint64_t n = uint64_t(r.rows().size()) * uint64_t(r.cols().size()) * samples_per_pixel;
        uint64_t now = done.fetch_add(n) + n;
        if (progress) {
            std::lock_guard<std::mutex> lock(progress_mutex);
            progress(now, total);
        }
    };

    int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range2d<int>(0, height, k_tile, 0, width, k_tile), render_tile,
                          tbb::simple_partitioner());
    });
    m_dropped = dropped.load();
}

Image CpuFrameRenderer::render(const RenderOptions& options, const ProgressFn& progress, AovImages* aovs) {
    const int width = options.width, height = options.height;
    const int channels = options.transparent ? 4 : 3;
    const uint32_t aov_mask = aovs ? options.aovs : 0u;
    Image image = with_memory_context(
        "--res " + std::to_string(width) + "x" + std::to_string(height) + ": the image",
        double(width) * double(height) * (channels + 7.0 * (aov_mask != 0)) * 4.0, "lower --res", [&] {
            if (aov_mask) *aovs = make_aov_images(width, height, aov_mask);
            return Image(width, height, channels);
        });
    // The samples in the pairwise tree of their indices (render/sample_sums.h), as a split render adds them.
    const uint32_t spp = uint32_t(options.spp);
    const std::vector<SampleBlock> blocks = aligned_blocks(0, spp);
    for_each_pixel(options, spp, progress, [&](int x, int y, const auto& leaf) {
        PixelSums acc = sum_block(blocks[0], leaf);
        for (size_t b = 1; b < blocks.size(); ++b) add_to(acc, sum_block(blocks[b], leaf));
        resolve_pixel(acc, spp, image.at(x, y), channels, aov_mask, aovs, size_t(y) * size_t(width) + size_t(x));
    });
    if (m_dropped > 0) spdlog::warn("render: {} samples were NaN or infinite and were dropped", m_dropped);
    return image;
}

PartialFilm CpuFrameRenderer::render_partial(const RenderOptions& options, uint32_t begin, uint32_t end,
                                             const ProgressFn& progress) {
    if (begin >= end || end > uint32_t(options.spp))
        throw Error("render: samples " + std::to_string(begin) + ".." + std::to_string(end) + " are not a range of " +
                    std::to_string(options.spp));
    PartialFilm film;
    film.width = options.width;
    film.height = options.height;
    film.spp = uint32_t(options.spp);
    film.first_hits = options.transparent || options.aovs != 0;
    const size_t pixels = size_t(options.width) * size_t(options.height);
    const std::vector<SampleBlock> blocks = aligned_blocks(begin, end);
    with_memory_context("--res " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                            ": the sums of " + std::to_string(blocks.size()) + " sample blocks",
                        double(pixels) * double(blocks.size()) * sizeof(PixelSums), "lower --res", [&] {
                            for (const SampleBlock& b : blocks)
                                film.planes.push_back({b, std::vector<PixelSums>(pixels)});
                            return 0;
                        });
    for_each_pixel(options, end - begin, progress, [&](int x, int y, const auto& leaf) {
        const size_t i = size_t(y) * size_t(options.width) + size_t(x);
        for (PartialFilm::Plane& plane : film.planes) plane.sums[i] = sum_block(plane.block, leaf);
    });
    film.dropped = m_dropped;
    return film;
}

}  // namespace npt::render::cpu
