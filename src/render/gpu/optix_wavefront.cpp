#include "render/gpu/optix_wavefront.h"

#include <optix.h>
#include <optix_stubs.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdlib>
#include <string>

#include "core/error.h"
#include "render/gpu/optix_context.h"
#include "render/gpu/optix_pipeline.h"

namespace npt::gpu {

WavefrontLoop::WavefrontLoop(Span<const media::VolumeView> host, Span<const media::VolumeView> device,
                             size_t max_paths, cudaStream_t stream)
    : m_stream(stream), m_pass(host, device, max_paths, stream) {
    if (!m_pass.any()) return;
    if (max_paths >= (size_t(1) << 31))  // the pass's segment items keep a path's index in 31 bits
        throw Error("WavefrontLoop: a wave of " + std::to_string(max_paths) +
                    " paths (at most 2^31 - 1): lower --res");
    m_max_paths = uint32_t(max_paths);
    m_path_words.allocate(max_paths * k_path_words, "the path states", "--res or --spp");
    m_queries.allocate(2 * max_paths, "the path states", "--res or --spp");
    m_events.allocate(max_paths, "the path states", "--res or --spp");
    m_queue.allocate(max_paths, "the path states", "--res or --spp");
    m_active[0].allocate(max_paths, "the path states", "--res or --spp");
    m_active[1].allocate(max_paths, "the path states", "--res or --spp");
}

void WavefrontLoop::run_wave(LaunchParams p, uint32_t slots, const OptixPrograms& programs,
                             LaunchParams* params) {
    const uint32_t n = uint32_t(size_t(p.width) * size_t(p.height) * slots);
    if (n == 0) return;
    if (n > m_max_paths)
        throw Error("WavefrontLoop: a wave of " + std::to_string(n) + " paths, built for " +
                    std::to_string(m_max_paths));
    const PathStore paths{m_path_words.data(), m_max_paths, m_queries.data(), m_events.data()};
    p.wave.paths = paths;
    p.wave.queue = m_queue.data();
    p.wave.nerf_slot = m_pass.nerf_slots();
    p.sample_count = slots;
    auto launch = [&](const uint32_t* active, uint32_t count) {
        p.wave.active = active;
        cuda_check(cudaMemcpyAsync(params, &p, sizeof p, cudaMemcpyHostToDevice, m_stream),
                   "cudaMemcpyAsync");
        // From pageable memory the copy is staged before the call returns, so p may change afterwards.
        optix_check(optixLaunch(programs.pipeline(), m_stream, CUdeviceptr(params), sizeof(LaunchParams),
                                &programs.sbt_wavefront(), count, 1, 1),
                    "optixLaunch");
    };
    // NERFPT_WAVEFRONT_STATS=1: where a wave's time goes (launches vs the NeRF pass), for benchmarks; the
    // extra synchronisation it needs costs a little time itself.
    static const bool stats = std::getenv("NERFPT_WAVEFRONT_STATS") != nullptr;
    using clock = std::chrono::steady_clock;
    double launch_s = 0.0, pass_s = 0.0;
    uint64_t launched = 0;
    int launches = 0;
    auto timed = [&](double& into, auto&& f) {
        const auto t0 = clock::now();
        f();
        if (stats) {
            cuda_check(cudaStreamSynchronize(m_stream), "rendering with OptiX");
            into += std::chrono::duration<double>(clock::now() - t0).count();
        }
    };
    uint32_t live = n;
    const uint32_t* active = nullptr;
    for (int cur = 0; live > 0; cur = 1 - cur) {
        timed(launch_s, [&] { launch(active, live); });
        launched += live;
        ++launches;
        uint32_t next = 0;
        timed(pass_s, [&] { next = m_pass.run(paths, m_queue.data(), active, live, m_active[cur].data()); });
        active = m_active[cur].data();
        live = next;
    }
    if (stats)
        spdlog::info("wavefront: {} launches, {} path-vertices, OptiX {:.2f} ms, NeRF pass {:.2f} ms ({})",
                     launches, launched, 1e3 * launch_s, 1e3 * pass_s, m_pass.stats());
}

}  // namespace npt::gpu
