// The wavefront path tracer's NeRF pass (render/gpu/nerf_segments.h) against the CPU's integrate_volumes on
// the same segments: a segment is left as a query by volume_segment (wavefront.h), marched and evaluated in
// batches on the GPU (fp16 tensor-core MLP) and written back into its path; the CPU marches the same segment
// with the same lattice offset through the fp32 MLPs. Registered only where a GPU exists (label gpu).
#include "render/gpu/nerf_segments.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "media/volume_integrator.h"
#include "nerf_pass_run.h"
#include "random_nerf_volume.h"
#include "render/gpu/device_scene.h"
#include "render/gpu/shared_math_check.h"

namespace npt {
namespace {

// Runs the pass with `tuning` on 4000 random segments and compares each with integrate_volumes.
void expect_pass_matches_cpu(const gpu::NerfPassTuning& tuning, const char* what) {
    SCOPED_TRACE(what);
    nerf::NerfConfig c;  // the default network: the shape the fp16 kernels take
    c.encoding.grid.log2_table_size = 14;
    c.encoding.finest_resolution = 128;
    c.occupancy.resolution = 32;
    std::mt19937 g(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    // Features up to 1, not 2 as elsewhere: fewer segments turn opaque at their first occupied cell.
    test::RandomNerfVolume nerf_volume(c, g, 1.0f, 0.5f);
    media::VolumeView v = nerf_volume.view;
    v.density_scale = 0.3f;
    v.emission_scale = 1.5f;
    const std::vector<media::VolumeView> host = {v};
    gpu::DeviceVolumes device(Span<const media::VolumeView>{host.data(), host.size()});

    const int n = 4000;
    cudaStream_t stream = nullptr;
    ASSERT_EQ(cudaStreamCreate(&stream), cudaSuccess);
    const int done = n / 8;  // paths after them already written to the image: not listed to go on
    gpu::NerfSegmentPass pass({host.data(), host.size()}, device.view(), size_t(n + done), stream);
    ASSERT_TRUE(pass.any());
    pass.set_tuning(tuning);
    const uint32_t slot_of_volume[1] = {0};

    std::vector<gpu::WavefrontPath> paths(size_t(n + done));  // phase Done, nothing queued
    std::vector<gpu::NerfQuery> queries(2 * paths.size());    // PathStore::queries: [2i + kind]
    std::vector<media::VolumeResult> cpu(n);
    std::vector<int> kind(n);
    int queued = 0;
    for (int i = 0; i < n; ++i) {
        float target_t = 0.0f;
        const Ray ray = test::ray_into_random_nerf_volume(g, &target_t);
        const float t_end = i % 3 == 0 ? target_t : INFINITY;  // a surface inside the cube
        const float xi = u(g);
        kind[i] = i % 4 == 0 ? 1 : 0;
        gpu::WavefrontPath& p = paths[i];
        p.phase = gpu::PathPhase::Scatter;
        media::VolumeResult inline_result;
        const bool q = gpu::volume_segment({host.data(), host.size()}, slot_of_volume, ray, 0.0f, t_end, xi,
                                           kind[i] == 1, &queries[2 * size_t(i) + size_t(kind[i])],
                                           &inline_result) != gpu::SegmentRoute::Inline;
        queued += q ? 1 : 0;
        // A segment that misses the cube is not queued and is empty.
        if (!q) {
            EXPECT_EQ(inline_result.transmittance, 1.0f);
        }
        cpu[i] = media::integrate_volumes({host.data(), host.size()}, ray, 0.0f, t_end, xi, kind[i] == 1);
    }
    EXPECT_GT(queued, n / 2);

    const test::NerfPassRun run = test::run_nerf_pass(pass, paths, queries,
                                                      std::vector<gpu::FlightEvent>(paths.size()));
    // The first n paths are in phase Scatter and go on; the done ones do not.
    ASSERT_EQ(run.going_on, uint32_t(n));
    for (int i = 0; i < n; ++i) ASSERT_EQ(run.listed[size_t(i)], uint32_t(i));
    const std::vector<gpu::WavefrontPath>& out = run.paths;
    cudaStreamDestroy(stream);

    // The only difference is fp16 rounding in the MLPs (2^-11 relative per operand). This network's outputs
    // are small (random initial weights), so its errors are absolute and tiny: the first GPU run saw at most
    // 5e-5. Required: transmittance within 2e-4 and radiance within 2e-4 + 0.1%, tighter than one march
    // step's share here (sigma ~0.3 per model unit over sqrt(3)/1024: ~5e-4 in T), so a sample gained or
    // lost, a wrong lattice offset or a shifted segment start fails. Up to 0.5% of the segments may differ
    // more (a cell decision flipped by rounding of a position, as the per-thread test in shared_math_gpu_test
    // sees; in the warp form also a lattice point within rounding of a skip's target, which march_continue
    // computes from another point of the same empty cell: 4 of 3889 segments on the H200, one sample each),
    // none by more than 0.1.
    int crossing = 0, outliers = 0, gross = 0;
    double worst = 0.0;
    for (int i = 0; i < n; ++i) {
        if (queries[2 * size_t(i) + size_t(kind[i])].slot == gpu::k_no_query) continue;
        const float t_gpu = kind[i] == 0 ? out[i].vol.transmittance : out[i].shadow_t;
        const Rgb l_gpu = kind[i] == 0 ? out[i].vol.radiance : Rgb(0.0f);
        const media::VolumeResult& r = cpu[i];
        if (r.transmittance < 0.9f) ++crossing;
        float err = std::fabs(t_gpu - r.transmittance);
        bool ok = err <= 2e-4f;
        for (int k = 0; k < 3; ++k) {
            const float d = std::fabs(l_gpu[k] - r.radiance[k]);
            err = std::max(err, d);
            ok = ok && d <= 1e-3f * std::fabs(r.radiance[k]) + 2e-4f;
        }
        worst = std::max(worst, double(err));
        if (!ok && ++outliers <= 5)
            std::printf("segment %d (kind %d): cpu T %.5f L %.5f | gpu T %.5f L %.5f\n", i, kind[i],
                        r.transmittance, r.radiance.x, t_gpu, l_gpu.x);
        if (err > 0.1f) ++gross;
    }
    std::printf(
        "%s: %d queued segments, %d crossing the medium, %d outside the bounds, worst difference %.2e (%s)\n",
        what, queued, crossing, outliers, worst, pass.stats().c_str());
    EXPECT_GT(crossing, queued / 4);  // the segments do see the medium
    EXPECT_LE(outliers, queued / 200);
    EXPECT_EQ(gross, 0);
}

TEST(NerfSegments, MatchTheCpuIntegratorWithinFp16Rounding) {
    ASSERT_TRUE(gpu::device_available());
    expect_pass_matches_cpu(gpu::NerfPassTuning::defaults(), "defaults");
}

// Both forms of a round alone, with rounds of at most 16 samples so that most segments are marched in several
// pieces (the cursor handed from round to round, the quota ending inside a warp's chunk of 32 points).
TEST(NerfSegments, ThreadRoundsAndWarpRoundsEachMatchTheCpu) {
    ASSERT_TRUE(gpu::device_available());
    gpu::NerfPassTuning threads;
    threads.warp_below = 0;
    threads.max_round = threads.max_warp_round = 16;
    expect_pass_matches_cpu(threads, "a thread per segment");
    gpu::NerfPassTuning warps;
    warps.warp_below = ~0u;
    warps.max_round = warps.max_warp_round = 16;
    expect_pass_matches_cpu(warps, "a warp per segment");
}

}  // namespace
}  // namespace npt
