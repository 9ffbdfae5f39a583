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

Image CpuFrameRenderer::render(const RenderOptions& options, const ProgressFn& progress, AovImages* aovs) {
    const int width = options.width, height = options.height, spp = options.spp;
    if (width != m_width || height != m_height)
        throw Error("render: " + std::to_string(width) + "x" + std::to_string(height) + " asked of a renderer prepared for " +
                    std::to_string(m_width) + "x" + std::to_string(m_height));
    EmbreeTracer tracer(*m_embree);
    const SceneView& sv = m_data->view();
    PathSettings ps;
    ps.max_depth = options.max_depth;
    ps.transparent_background = options.transparent;
    const int channels = options.transparent ? 4 : 3;
    const uint32_t aov_mask = aovs ? options.aovs : 0u;
    // The camera ray's first hit is recorded only where the film needs it.
    const bool record_first = options.transparent || aov_mask != 0;

    Image image = with_memory_context(
        "--res " + std::to_string(width) + "x" + std::to_string(height) + ": the image",
        double(width) * double(height) * (channels + 7.0 * (aov_mask != 0)) * 4.0, "lower --res", [&] {
            if (aov_mask) *aovs = make_aov_images(width, height, aov_mask);
            return Image(width, height, channels);
        });
    const uint64_t total = uint64_t(width) * uint64_t(height) * uint64_t(spp);
    std::atomic<uint64_t> done{0};
    std::atomic<uint64_t> dropped{0};
    std::mutex progress_mutex;

    auto render_tile = [&](const tbb::blocked_range2d<int>& r) {
        for (int y = r.rows().begin(); y < r.rows().end(); ++y)
            for (int x = r.cols().begin(); x < r.cols().end(); ++x) {
                Rgb sum(0.0f);
                FirstHitSums first_sums;
                for (int s = 0; s < spp; ++s) {
                    SobolSampler sampler(options.seed, uint32_t(x), uint32_t(y), uint32_t(s));
                    Ray ray = generate_camera_ray(sv.camera, x, y, sampler.next_2d());
                    FirstHit first;
                    Rgb l = trace_path(sv, tracer, ray, sampler, ps, record_first ? &first : nullptr);
                    add_first_hit(first_sums, first);  // a dropped sample's coverage still counts
                    if (is_finite(l)) {
                        sum += l;
                    } else {
                        dropped.fetch_add(1, std::memory_order_relaxed);
                    }
                }
                float* px = image.at(x, y);
                px[0] = sum.x / float(spp);
                px[1] = sum.y / float(spp);
                px[2] = sum.z / float(spp);
                if (channels == 4) px[3] = 1.0f - first_sums.escaped / float(spp);
                if (aov_mask) {
                    const FirstHitAovs a = resolve_first_hit(first_sums.weight, first_sums.albedo,
                                                             first_sums.normal, first_sums.distance);
                    aovs->set(size_t(y) * size_t(width) + size_t(x), a.albedo, a.normal, a.depth);
                }
            }
        uint64_t n = uint64_t(r.rows().size()) * uint64_t(r.cols().size()) * uint64_t(spp);
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
    if (dropped > 0) spdlog::warn("render: {} samples were NaN or infinite and were dropped", dropped.load());
    return image;
}

}  // namespace npt::render::cpu
