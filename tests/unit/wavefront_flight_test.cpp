// The wavefront path tracer's hand-over of a relit NeRF (render/gpu/wavefront.h, volume_segment with a free
// flight): a radiance ray's segment through a relit NeRF alone is left as a query with the flight's target and the
// map from model distance to world t; its shadow rays' segments as the emissive kind's transmittance queries; the
// rest is integrated in place, free flight included. Here, on the CPU, the query is marched the way the GPU's NeRF
// pass marches it (march_ray_visit from the query's ray, lattice offset and end; the event where the optical depth
// first reaches the target; the event's t recovered from its position, flight_event_t) and must give
// integrate_volumes' event. The GPU pass itself is tested on a GPU (tests/gpu/nerf_flight_test.cpp).
// Tolerances: the CPU integrator evaluates the MLPs batched (matrix products), the query per point: float
// rounding, 1e-4 relative in the optical depth, which can move an event by a sample only where the target lies
// within that of a sample's depth (none of the 300 segments here).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "media/placement.h"
#include "random_nerf_volume.h"
#include "render/gpu/wavefront.h"

namespace npt {
namespace {

struct QueryFlight {
    bool event = false;
    float t = 0.0f;
    Vec3 p{0.0f};
};

// The NeRF pass's free flight over a queried segment (nerf_segment_kernels.cu flight_step, flight_event_t), per
// point. Every sample's t as the pass recovers it from the position must be the march's own: bit for bit on a
// uniform lattice, within float rounding (1e-6 of t) with a cone angle. `checked` counts the samples compared.
QueryFlight march_flight_query(const media::VolumeView& v, const gpu::NerfQuery& q, int* checked) {
    nerf::MarchParams mp = v.nerf.march;
    mp.t_max = q.t_max;
    nerf::MarchCursor c;
    QueryFlight r;
    if (!nerf::march_start(mp, v.nerf.occupancy, q.ray, q.xi, &c)) return r;
    const float t0 = c.t0;
    float log_t = 0.0f;
    nerf::march_continue(mp, v.nerf.occupancy, q.ray, c, [&](const nerf::MarchSample& s) {
        const float t = gpu::flight_event_t(mp, q.ray, t0, q.t_world, q.world_per_model, s.position);
        const float expected = q.t_world + s.t * q.world_per_model;  // march_relit's
        if (mp.cone_angle == 0.0f)
            EXPECT_EQ(t, expected);
        else
            EXPECT_NEAR(t, expected, 1e-6f * std::fabs(expected));
        ++*checked;
        const float x = v.nerf.field.density(s.position) * v.density_scale * s.dt;
        if (!(x > 0.0f)) return true;
        log_t -= x;
        if (-log_t < q.target) return true;
        r.event = true;
        r.t = t;
        r.p = s.position;
        return false;
    });
    return r;
}

// levels 4, features up to 2, half the cells occupied, relit; a density scale other than 1 so that it is tested.
struct Fixture {
    std::mt19937 g{5};
    test::RandomNerfVolume volume{config(), g, 2.0f, 0.5f};
    media::VolumeView& nerf_volume = volume.view;
    explicit Fixture(float cone_angle) {
        nerf_volume.nerf.relit = true;
        nerf_volume.density_scale = 0.4f;
        nerf_volume.nerf.march.cone_angle = cone_angle;
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

void expect_queued_flights_match(float cone_angle) {
    Fixture f(cone_angle);
    const media::VolumeView volumes[1] = {f.nerf_volume};
    const uint32_t slots[1] = {0};
    std::mt19937 g(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    int queued = 0, events = 0, through = 0, checked = 0;
    for (int i = 0; i < 300; ++i) {
        float target_t = 0.0f;
        const Ray ray = test::ray_into_random_nerf_volume(g, &target_t);
        const float t_end = i % 3 == 0 ? target_t : INFINITY;
        const float xi = u(g);
        media::FreeFlight flight;
        flight.target = media::free_flight_target(u(g));
        gpu::NerfQuery q;
        media::VolumeResult vol;
        media::FreeFlight cpu = flight;
        const media::VolumeResult expected =
            media::integrate_volumes({volumes, 1}, ray, 0.0f, t_end, xi, false, &cpu);
        const gpu::SegmentRoute route =
            gpu::volume_segment({volumes, 1}, slots, ray, 0.0f, t_end, xi, false, &q, &vol, &flight);
        // A relit NeRF alone neither emits nor attenuates the segment: its flight does (trace_path's throughput is
        // the no-event probability times this).
        EXPECT_EQ(expected.transmittance, 1.0f);
        EXPECT_EQ(vol.transmittance, 1.0f);
        EXPECT_EQ(vol.radiance.x, 0.0f);
        EXPECT_FALSE(flight.event);  // left to the pass
        if (route == gpu::SegmentRoute::Inline) {  // missed the cube
            EXPECT_EQ(q.slot, gpu::k_no_query);
            EXPECT_FALSE(cpu.event);
            continue;
        }
        ASSERT_EQ(route, gpu::SegmentRoute::Flight);
        ++queued;
        EXPECT_EQ(q.slot, 0u);
        EXPECT_EQ(q.target, flight.target);
        const QueryFlight got = march_flight_query(f.nerf_volume, q, &checked);
        ASSERT_EQ(got.event, cpu.event) << i;
        if (!got.event) {
            ++through;
            continue;
        }
        ++events;
        EXPECT_EQ(cpu.volume, 0);
        EXPECT_NEAR(got.t, cpu.t, 1e-6f * std::fabs(cpu.t)) << i;
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(got.p[k], cpu.p_model[k], 1e-6f) << i;
    }
    EXPECT_GT(queued, 100);
    EXPECT_GT(events, 30);  // both outcomes are tested
    EXPECT_GT(through, 30);
    EXPECT_GT(checked, 1000);
}

TEST(WavefrontFlight, AQueuedFlightFindsTheIntegratorsEventOnAUniformLattice) { expect_queued_flights_match(0.0f); }

TEST(WavefrontFlight, AQueuedFlightFindsTheIntegratorsEventWithAConeAngle) {
    expect_queued_flights_match(1.0f / 256.0f);
}

// The shadow rays through a relit NeRF are queued as the emissive kind's transmittance (the pass composites them
// without emission), which is march_relit_nerf's absorption: the same sums of sigma dt, the same cut-off.
TEST(WavefrontFlight, ShadowSegmentsAreQueuedAsTransmittance) {
    Fixture f(0.0f);
    const media::VolumeView volumes[1] = {f.nerf_volume};
    const uint32_t slots[1] = {0};
    std::mt19937 g(9);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    int queued = 0, seen = 0;
    for (int i = 0; i < 200; ++i) {
        float target_t = 0.0f;
        const Ray ray = test::ray_into_random_nerf_volume(g, &target_t);
        const float xi = u(g);
        gpu::NerfQuery q;
        media::VolumeResult vol;
        const gpu::SegmentRoute route =
            gpu::volume_segment({volumes, 1}, slots, ray, 0.0f, INFINITY, xi, true, &q, &vol);
        const media::VolumeResult expected = media::integrate_volumes({volumes, 1}, ray, 0.0f, INFINITY, xi, true);
        if (route == gpu::SegmentRoute::Inline) continue;
        ASSERT_EQ(route, gpu::SegmentRoute::Queued);
        ++queued;
        // The pass's shadow composite (nerf_segment_kernels.cu: add_nerf_sample without emission).
        nerf::MarchParams mp = f.nerf_volume.nerf.march;
        mp.t_max = q.t_max;
        media::Accumulator acc;
        acc.with_emission = false;
        nerf::march_ray_visit(mp, f.nerf_volume.nerf.occupancy, q.ray, q.xi, [&](const nerf::MarchSample& s) {
            media::add_nerf_sample(acc, f.nerf_volume.nerf.field.density(s.position), Rgb(0.0f), s.dt,
                                   f.nerf_volume.density_scale, 1.0f);
            return !acc.done();
        });
        const float got = acc.done() ? 0.0f : std::exp(acc.log_t);
        if (expected.transmittance < 0.95f) ++seen;
        EXPECT_NEAR(got, expected.transmittance, 1e-4f) << i;
    }
    EXPECT_GT(queued, 100);
    EXPECT_GT(seen, 50);
}

// What the pass does not take is integrated in place with the flight, as trace_path would: a relit NeRF without a
// pass slot, and a radiance ray with no flight (absorption only, march_relit_nerf's other branch).
TEST(WavefrontFlight, OtherRelitSegmentsAreIntegratedInPlace) {
    Fixture f(0.0f);
    const media::VolumeView volumes[1] = {f.nerf_volume};
    const uint32_t no_slot[1] = {gpu::k_no_query}, slots[1] = {0};
    const Ray ray{Vec3(0.1f, 0.2f, 3.0f), Vec3(0.0f, 0.0f, -1.0f)};
    gpu::NerfQuery q;
    media::VolumeResult r;

    media::FreeFlight flight, expected_flight;
    flight.target = expected_flight.target = 0.005f;  // below the optical depth checked below
    EXPECT_EQ(gpu::volume_segment({volumes, 1}, no_slot, ray, 0.0f, INFINITY, 0.3f, false, &q, &r, &flight),
              gpu::SegmentRoute::Inline);
    const media::VolumeResult e =
        media::integrate_volumes({volumes, 1}, ray, 0.0f, INFINITY, 0.3f, false, &expected_flight);
    EXPECT_EQ(q.slot, gpu::k_no_query);
    ASSERT_TRUE(expected_flight.event);  // this ray does scatter
    EXPECT_TRUE(flight.event);
    EXPECT_EQ(flight.t, expected_flight.t);
    EXPECT_EQ(flight.volume, 0);
    EXPECT_EQ(r.transmittance, e.transmittance);

    EXPECT_EQ(gpu::volume_segment({volumes, 1}, slots, ray, 0.0f, INFINITY, 0.3f, false, &q, &r),
              gpu::SegmentRoute::Inline);
    const media::VolumeResult absorbed = media::integrate_volumes({volumes, 1}, ray, 0.0f, INFINITY, 0.3f, false);
    EXPECT_LT(absorbed.transmittance, 0.99f);
    EXPECT_EQ(r.transmittance, absorbed.transmittance);
}

}  // namespace
}  // namespace npt
