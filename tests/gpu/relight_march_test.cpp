// The relight stage's wavefront march on the GPU (FieldQuery::march of the CUDA query: rounds, fp32 field and
// compositing on the device) against the CPU's march (march_wavefront with the CPU query), in all three
// modes, on a model with random weights. The two run the same per-point code in fp32; they differ by float
// rounding only (fused multiply-adds), so transmittances and colours agree to ~1e-5 and an event lands on
// another sample only where the optical depth passes its target within that rounding.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/rng.h"
#include "nerf/backend/nerf_backend.h"
#include "nerf/relight/field_query.h"
#include "nerf/relight/wavefront_march.h"
#include "relit_test_fields.h"

namespace npt::nerf {
namespace {

std::vector<WaveRay> random_rays(size_t n, uint64_t seed) {
    Pcg32 rng(seed, 5);
    std::vector<WaveRay> rays(n);
    for (WaveRay& r : rays) {
        const Vec3 o(rng.next_float(), rng.next_float(), rng.next_float());
        Vec3 d;
        do d = Vec3(2 * rng.next_float() - 1, 2 * rng.next_float() - 1, 2 * rng.next_float() - 1);
        while (length_squared(d) > 1.0f || length_squared(d) < 1e-4f);
        r.ray = Ray{o, normalize(d)};
        r.jitter = rng.next_float();
        r.tau_target = -std::log1p(-0.999f * rng.next_float());
        r.has_event = true;  // stale results: the march must overwrite them
        r.transmittance = -1.0f;
    }
    return rays;
}

class RelightMarchGpu : public ::testing::TestWithParam<WaveMode> {};

TEST_P(RelightMarchGpu, MatchesTheCpuMarch) {
    const WaveMode mode = GetParam();
    const NerfModel model = test::random_relightable_model(3, false, true);
    const std::vector<WaveRay> rays = random_rays(20000, 9);
    std::vector<WaveRay> cpu = rays, gpu = rays;
    const std::unique_ptr<FieldQuery> cpu_query = make_cpu_field_query(model);
    const std::unique_ptr<FieldQuery> gpu_query = make_field_query(Backend::cuda, model);
    march_wavefront(model, *cpu_query, cpu, mode);
    march_wavefront(model, *gpu_query, gpu, mode);

    size_t events = 0, event_mismatch = 0, partial = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
        const WaveRay &c = cpu[i], &g = gpu[i];
        ASSERT_GE(g.transmittance, 0.0f) << "ray " << i << ": not written";
        if (mode == WaveMode::event) {
            events += c.has_event;
            if (c.has_event != g.has_event || length(c.event_position - g.event_position) > 1e-5f) {
                ++event_mismatch;
                continue;
            }
            EXPECT_NEAR(g.transmittance, c.transmittance, 1e-4f + 1e-4f * c.transmittance) << "ray " << i;
            continue;
        }
        EXPECT_FALSE(g.has_event) << i;
        partial += c.transmittance > 0.01f && c.transmittance < 0.99f;
        EXPECT_NEAR(g.transmittance, c.transmittance, 1e-4f + 1e-4f * c.transmittance) << "ray " << i;
        EXPECT_NEAR(g.depth, c.depth, 1e-4f + 1e-4f * std::fabs(c.depth)) << "ray " << i;
        for (int ch = 0; ch < 3; ++ch)
            EXPECT_NEAR(g.radiance[ch], c.radiance[ch], 1e-4f + 1e-4f * c.radiance[ch]) << "ray " << i;
    }
    if (mode == WaveMode::event) {
        // The test means something only if many rays end at an event and many pass through.
        EXPECT_GT(events, rays.size() / 10);
        EXPECT_LT(events, rays.size() * 9 / 10);
        EXPECT_LE(event_mismatch, rays.size() / 1000) << "of " << events << " events";
    } else {
        EXPECT_GT(partial, rays.size() / 10) << "too few rays partly through the model to compare";
    }
}

INSTANTIATE_TEST_SUITE_P(Modes, RelightMarchGpu,
                         ::testing::Values(WaveMode::radiance, WaveMode::event, WaveMode::depth));

}  // namespace
}  // namespace npt::nerf
