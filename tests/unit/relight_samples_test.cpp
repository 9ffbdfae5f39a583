// The relight stage's surface points (nerf/relight/relight_samples.h) on a NeRF trained for a few seconds on
// the analytic sphere scene: every event draw of a point lies on that point's camera ray, close to the
// surface, and the draws spread over the surface's depth instead of repeating one position.
#include "nerf/relight/relight_samples.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "nerf/relight/field_query.h"
#include "nerf/trainer.h"
#include "nerf_test_scene.h"

namespace npt::nerf {
namespace {

NerfModel trained_spheres(const Dataset& train) {
    NerfModel m =
        create_model(test::small_sphere_config(), 1.0f, ngp_world_to_model(train.scale, train.offset));
    Trainer t(m, train);
    for (int i = 0; i < 300; ++i) t.step();
    t.sync_model();
    m.training.reset();
    return m;
}

TEST(RelightSamples, EventDrawsLieOnThePointsCameraRayNearTheSurface) {
    const Dataset train = test::make_sphere_scene({.views = 20, .size = 32, .view_seed = 1});
    const NerfModel model = trained_spheres(train);
    std::unique_ptr<FieldQuery> query = make_cpu_field_query(model);
    RelightSampleSettings ss;
    ss.points = 256;
    ss.directions = 4;
    ss.event_draws = 4;
    ss.min_alpha = 0.5f;  // 32 px images: edge pixels are rarely fully opaque
    const RelightSamples s = gather_relight_samples(model, train, *query, ss);
    ASSERT_GT(s.size(), 128u);
    ASSERT_EQ(s.draws, 4);
    ASSERT_EQ(s.draw.size(), s.size() * 4);
    EXPECT_EQ(s.lit, s.size());  // no borrowing pixels: every sample is lit by its own directions
    size_t spread = 0, near = 0;
    double max_off_ray = 0;
    for (size_t i = 0; i < s.size(); ++i) {
        EXPECT_EQ(s.draw_position(i, 0).x, s.position[i].x);  // draw 0 is the shaded point
        bool differs = false;
        for (uint32_t m = 1; m < 4; ++m) {
            const Vec3 d = s.draw_position(i, m) - s.position[i];
            const float along = dot(d, s.wo[i]);  // wo: unit, toward the camera, along the ray
            max_off_ray = std::max(max_off_ray, double(length(d - s.wo[i] * along)));
            near += std::fabs(along) < 0.15f;
            differs |= length(d) > 1e-6f;
        }
        spread += differs;
    }
    // On the ray to float rounding (model units; the unit cube); nearly all near the first draw: this
    // 300-step model's surfaces are soft (draws spread +-0.03 around the first, 90% within +-0.12), a draw in
    // empty space or on the far side of the scene would lie 0.3 away or more.
    EXPECT_LT(max_off_ray, 1e-4);
    EXPECT_GT(near, s.size() * 3 * 9 / 10);
    // Two independent draws from a surface a few march steps thick rarely land on the same sample.
    EXPECT_GT(spread, s.size() / 2);
}

// Borrowing pixels come after the lit points with their own camera ray, target and draws; each borrows the
// light of a lit point within the radius whose normal faces its camera.
TEST(RelightSamples, BorrowingPixelsTakeTheLightOfANearbyFacingPoint) {
    const Dataset train = test::make_sphere_scene({.views = 20, .size = 32, .view_seed = 1});
    const NerfModel model = trained_spheres(train);
    std::unique_ptr<FieldQuery> query = make_cpu_field_query(model);
    RelightSampleSettings ss;
    ss.points = 256;
    ss.directions = 4;
    ss.event_draws = 2;
    ss.min_alpha = 0.5f;
    ss.borrowing_pixels = 1024;
    ss.borrow_radius = 0.05f;
    const RelightSamples s = gather_relight_samples(model, train, *query, ss);
    ASSERT_GT(s.lit, 128u);
    ASSERT_EQ(s.normal.size(), s.lit);
    ASSERT_EQ(s.visibility.size(), s.lit * 4);
    const size_t borrowing = s.size() - s.lit;
    EXPECT_GT(borrowing, 512u);  // most opaque pixels' events have a lit point within 0.05
    EXPECT_LE(borrowing, 1024u);
    ASSERT_EQ(s.donor.size(), borrowing);
    ASSERT_EQ(s.draw.size(), s.size() * 2);
    ASSERT_EQ(s.target.size(), s.size());
    for (size_t i = s.lit; i < s.size(); ++i) {
        const uint32_t d = s.light_of(i);
        ASSERT_LT(d, s.lit);
        EXPECT_LT(length(s.position[i] - s.position[d]), 0.05f);
        EXPECT_GT(dot(s.normal[d], s.wo[i]), 0.1f);
        EXPECT_EQ(s.draw_position(i, 0).x, s.position[i].x);
        // The nearest facing lit point (by brute force), whichever grid found it.
        float nearest = 1e30f;
        for (size_t j = 0; j < s.lit; ++j)
            if (dot(s.normal[j], s.wo[i]) > 0.1f) nearest = std::min(nearest, length(s.position[j] - s.position[i]));
        EXPECT_FLOAT_EQ(length(s.position[d] - s.position[i]), nearest);
    }
    for (size_t i = 0; i < s.lit; ++i) EXPECT_EQ(s.light_of(i), i);

    // Dense points: the donor is looked for within the points' spacing first (2.5x the median distance of the
    // 4th neighbour, ~0.05 here: well under the radius, so that search is the one exercised), and is still the
    // nearest facing one.
    ss.points = 4096;
    ss.borrow_radius = 0.1f;
    const RelightSamples dense = gather_relight_samples(model, train, *query, ss);
    std::vector<float> fourth;
    for (size_t i = 0; i < dense.lit; i += 64) {
        std::vector<float> d;
        for (size_t j = 0; j < dense.lit; ++j)
            if (j != i) d.push_back(length(dense.position[j] - dense.position[i]));
        std::nth_element(d.begin(), d.begin() + 3, d.end());
        fourth.push_back(d[3]);
    }
    std::nth_element(fourth.begin(), fourth.begin() + std::ptrdiff_t(fourth.size() / 2), fourth.end());
    ASSERT_LT(2.5f * fourth[fourth.size() / 2], 0.6f * ss.borrow_radius);
    ASSERT_GT(dense.size(), dense.lit + 512);
    for (size_t i = dense.lit; i < dense.size(); ++i) {
        float nearest = 1e30f;
        for (size_t j = 0; j < dense.lit; ++j)
            if (dot(dense.normal[j], dense.wo[i]) > 0.1f)
                nearest = std::min(nearest, length(dense.position[j] - dense.position[i]));
        ASSERT_FLOAT_EQ(length(dense.position[dense.light_of(i)] - dense.position[i]), nearest) << i;
    }
    ss.borrow_radius = 0.0f;
    EXPECT_THROW(gather_relight_samples(model, train, *query, ss), Error);
}

TEST(RelightSamples, PooledNeighboursAreNearbyLitPointsWithAgreeingNormals) {
    const Dataset train = test::make_sphere_scene({.views = 20, .size = 32, .view_seed = 1});
    const NerfModel model = trained_spheres(train);
    std::unique_ptr<FieldQuery> query = make_cpu_field_query(model);
    RelightSampleSettings ss;
    ss.points = 512;
    ss.directions = 4;
    ss.event_draws = 1;
    ss.min_alpha = 0.5f;
    ss.borrowing_pixels = 64;
    ss.borrow_radius = 0.08f;
    ss.pooled_neighbours = 3;
    const RelightSamples s = gather_relight_samples(model, train, *query, ss);
    ASSERT_GT(s.lit, 256u);
    ASSERT_EQ(s.neighbours, 3);
    ASSERT_EQ(s.neighbour.size(), s.lit * 3);
    size_t pooled = 0;
    std::vector<uint32_t> dirs;
    for (size_t i = 0; i < s.lit; ++i) {
        float last = 0.0f;
        bool ended = false;
        for (int m = 0; m < 3; ++m) {
            const uint32_t q = s.neighbour[i * 3 + m];
            if (q == RelightSamples::k_no_neighbour) {
                ended = true;
                continue;
            }
            ASSERT_FALSE(ended) << "a neighbour after the list's end";
            ASSERT_LT(q, s.lit);
            ASSERT_NE(q, i);
            const float d = length(s.position[q] - s.position[i]);
            EXPECT_LT(d, 0.08f);
            EXPECT_GE(d, last);  // nearest first
            last = d;
            EXPECT_GT(dot(s.normal[q], s.normal[i]), 0.9f);
            ++pooled;
        }
        // The point's own directions first, then each neighbour's.
        s.light_directions(uint32_t(i), dirs);
        ASSERT_GE(dirs.size(), 4u);
        for (uint32_t k = 0; k < 4; ++k) EXPECT_EQ(dirs[k], uint32_t(i) * 4 + k);
        if (s.neighbour[i * 3] != RelightSamples::k_no_neighbour) EXPECT_EQ(dirs[4], s.neighbour[i * 3] * 4);
    }
    EXPECT_GT(pooled, s.lit * 2);  // 512 points on two spheres: most have 3 neighbours within 0.08
    // Pooled points draw their own elevations within the strata (alone, every point has the strata's
    // midpoints), so a point and its neighbours do not repeat them: direction k's cosine to the normal lies in
    // stratum k, and varies between points.
    float lowest = 1.0f, highest = 0.0f;
    for (size_t i = 0; i < s.lit; ++i)
        for (int k = 0; k < 4; ++k) {
            const float z = dot(s.dir[i * 4 + size_t(k)], s.normal[i]);
            EXPECT_LE(z, 1.0f - float(k) / 4.0f + 1e-4f);
            EXPECT_GE(z, 1.0f - float(k + 1) / 4.0f - 1e-4f);
            if (k == 0) {
                lowest = std::min(lowest, z);
                highest = std::max(highest, z);
            }
        }
    EXPECT_GT(highest - lowest, 0.2f);  // spread over most of the stratum [0.75, 1]
    // Borrowing pixels shade with their donor's pooled directions.
    ASSERT_GT(s.size(), s.lit);
    std::vector<uint32_t> donor_dirs;
    s.light_directions(s.light_of(s.lit), dirs);
    s.light_directions(s.donor[0], donor_dirs);
    EXPECT_EQ(dirs, donor_dirs);
    ss.pooled_neighbours = -1;
    EXPECT_THROW(gather_relight_samples(model, train, *query, ss), Error);
}

TEST(RelightSamples, ZeroEventDrawsIsAnError) {
    const Dataset train = test::make_sphere_scene({.views = 4, .size = 16, .view_seed = 1});
    const NerfModel model =
        create_model(test::small_sphere_config(), 1.0f, ngp_world_to_model(train.scale, train.offset));
    std::unique_ptr<FieldQuery> query = make_cpu_field_query(model);
    RelightSampleSettings ss;
    ss.event_draws = 0;
    EXPECT_THROW(gather_relight_samples(model, train, *query, ss), Error);
}

}  // namespace
}  // namespace npt::nerf
