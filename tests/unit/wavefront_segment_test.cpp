// The wavefront path tracer's hand-over (render/gpu/wavefront.h, volume_segment): a segment that crosses only a
// NeRF is left as a model-space query for the GPU's NeRF pass, everything else is integrated where it is. The
// GPU pass itself is tested on a GPU (tests/gpu/nerf_segments_test.cpp); here, on the CPU, the query is marched
// the way that pass marches it (march_ray_visit from the query's ray, lattice offset and end, media::Accumulator)
// and must give integrate_volumes' result, so the hand-over loses nothing. Tolerance: the CPU integrator
// evaluates the MLPs batched (matrix products) and the query per point: float rounding, 1e-4 relative.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/transform.h"
#include "media/placement.h"
#include "random_nerf_volume.h"
#include "render/gpu/wavefront.h"

namespace npt {
namespace {

media::VolumeResult march_query(const media::VolumeView& v, const gpu::NerfQuery& q, bool emission) {
    nerf::MarchParams mp = v.nerf.march;
    mp.t_max = q.t_max;
    media::Accumulator acc;
    acc.with_emission = emission;
    nerf::march_ray_visit(mp, v.nerf.occupancy, q.ray, q.xi, [&](const nerf::MarchSample& s) {
        float sigma = 0.0f;
        Rgb rgb(0.0f);
        v.nerf.field.query(s.position, q.ray.d, &sigma, &rgb);
        media::add_nerf_sample(acc, sigma, rgb, s.dt, v.density_scale, v.emission_scale);
        return !acc.done();
    });
    media::VolumeResult r;
    r.radiance = acc.radiance;
    r.transmittance = acc.done() ? 0.0f : std::exp(acc.log_t);
    return r;
}

// levels 4, features up to 2, half the cells occupied; scales other than 1 so that they are tested too.
struct SegmentFixture {
    std::mt19937 g{3};
    test::RandomNerfVolume volume{config(), g, 2.0f, 0.5f};
    media::VolumeView& nerf_volume = volume.view;
    SegmentFixture() {
        nerf_volume.density_scale = 0.4f;
        nerf_volume.emission_scale = 1.3f;
    }
    static nerf::NerfConfig config() {
        nerf::NerfConfig c;
        c.encoding.grid.levels = 4;
        c.encoding.grid.log2_table_size = 12;
        c.encoding.finest_resolution = 64;
        c.occupancy.resolution = 16;
        return c;
    }
};

bool near(float a, float b) { return std::fabs(a - b) <= 1e-4f * std::max(1.0f, std::fabs(b)); }

TEST(WavefrontSegment, AQueuedNerfSegmentMarchesToTheIntegratorsResult) {
    SegmentFixture f;
    const media::VolumeView volumes[1] = {f.nerf_volume};
    const uint32_t slots[1] = {0};
    std::mt19937 g(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    int queued = 0, seen = 0;
    for (int i = 0; i < 300; ++i) {
        float target_t = 0.0f;
        const Ray ray = test::ray_into_random_nerf_volume(g, &target_t);
        const float t_end = i % 3 == 0 ? target_t : INFINITY;
        const float xi = u(g);
        const bool shadow = i % 4 == 0;
        gpu::NerfQuery q;
        media::VolumeResult inline_result;
        const bool deferred = gpu::volume_segment({volumes, 1}, slots, ray, 0.0f, t_end, xi, shadow, &q,
                                                  &inline_result) == gpu::SegmentRoute::Queued;
        const media::VolumeResult expected = media::integrate_volumes({volumes, 1}, ray, 0.0f, t_end, xi, shadow);
        if (!deferred) {  // missed the cube: nothing there
            EXPECT_EQ(q.slot, gpu::k_no_query);
            EXPECT_EQ(inline_result.transmittance, 1.0f);
            EXPECT_EQ(expected.transmittance, 1.0f);
            continue;
        }
        ++queued;
        EXPECT_EQ(q.slot, 0u);
        const media::VolumeResult got = march_query(f.nerf_volume, q, !shadow);
        if (expected.transmittance < 0.95f) ++seen;
        EXPECT_TRUE(near(got.transmittance, expected.transmittance)) << i << ": " << got.transmittance << " vs "
                                                                     << expected.transmittance;
        for (int k = 0; k < 3; ++k)
            EXPECT_TRUE(near(got.radiance[k], expected.radiance[k])) << i << " channel " << k;
    }
    EXPECT_GT(queued, 100);
    EXPECT_GT(seen, 50);  // the segments cross the medium
}

// What the NeRF pass does not take is integrated in place, as trace_path would: a NeRF without a pass slot, and
// a ray crossing two volumes (a grid cube around the NeRF's).
TEST(WavefrontSegment, OtherSegmentsAreIntegratedInPlace) {
    SegmentFixture f;
    std::vector<float> density(8 * 8 * 8, 0.5f);
    std::vector<Vec3> color(density.size(), Vec3(0.2f, 0.4f, 0.6f));
    media::VolumeView grid;
    grid.kind = media::VolumeKind::Grid;
    grid.grid.nx = grid.grid.ny = grid.grid.nz = 8;
    grid.grid.density = density.data();
    grid.grid.color = color.data();
    grid.grid.local_to_index = media::affine_from(Mat4::translation(3.5, 3.5, 3.5) * Mat4::scale(4.0, 4.0, 4.0));
    grid.world_to_local = media::affine_from(Mat4::scale(0.5, 0.5, 0.5));  // a cube of side 4 around the NeRF
    const media::VolumeView both[2] = {grid, f.nerf_volume};
    const uint32_t no_slot[1] = {gpu::k_no_query}, slots[2] = {gpu::k_no_query, 0};
    const Ray ray{Vec3(0.1f, 0.2f, 3.0f), Vec3(0.0f, 0.0f, -1.0f)};
    gpu::NerfQuery q;
    media::VolumeResult r;

    EXPECT_EQ(gpu::volume_segment({&f.nerf_volume, 1}, no_slot, ray, 0.0f, INFINITY, 0.3f, false, &q, &r),
              gpu::SegmentRoute::Inline);
    media::VolumeResult e = media::integrate_volumes({&f.nerf_volume, 1}, ray, 0.0f, INFINITY, 0.3f, false);
    EXPECT_EQ(q.slot, gpu::k_no_query);
    EXPECT_LT(e.transmittance, 0.99f);
    EXPECT_EQ(r.transmittance, e.transmittance);
    EXPECT_EQ(r.radiance.x, e.radiance.x);

    EXPECT_EQ(gpu::volume_segment({both, 2}, slots, ray, 0.0f, INFINITY, 0.3f, false, &q, &r),
              gpu::SegmentRoute::Inline);
    e = media::integrate_volumes({both, 2}, ray, 0.0f, INFINITY, 0.3f, false);
    EXPECT_EQ(q.slot, gpu::k_no_query);
    EXPECT_EQ(r.transmittance, e.transmittance);
    EXPECT_EQ(r.radiance.y, e.radiance.y);
}

}  // namespace
}  // namespace npt
