// The relight stage's surface points (nerf/relight/relight_samples.h) on a NeRF trained for a few seconds on
// the analytic sphere scene: every event draw of a point lies on that point's camera ray, close to the
// surface, and the draws spread over the surface's depth instead of repeating one position.
#include "nerf/relight/relight_samples.h"

#include <gtest/gtest.h>

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
    }
    for (size_t i = 0; i < s.lit; ++i) EXPECT_EQ(s.light_of(i), i);
    ss.borrow_radius = 0.0f;
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
