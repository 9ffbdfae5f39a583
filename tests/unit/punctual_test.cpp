// Tests of point, spot and directional lights against hand-computed values: inverse-square falloff, the glTF
// spot attenuation, and the delta-light sample fields.
#include "lights/punctual.h"

#include <gtest/gtest.h>

#include <cmath>

#include "lights/light.h"
#include "lights/light_set.h"

namespace npt::lights {
namespace {

scene::Scene one_light(scene::PunctualLight p) {
    scene::Scene s;
    s.lights.push_back(p);
    return s;
}

TEST(PunctualLight, PointInverseSquare) {
    scene::PunctualLight p;
    p.type = scene::PunctualType::Point;
    p.position = {1, 2, 3};
    p.intensity = {4, 8, 12};
    scene::Scene scene = one_light(p);
    LightSet set(scene);
    LightSample s;
    // From (1, 2, 1) the light is 2 above: radiance I / 4 = (1, 2, 3), along +Z.
    ASSERT_TRUE(sample_light(set.view(), {1, 2, 1}, 0.5f, {0.3f, 0.3f}, &s));
    EXPECT_TRUE(s.is_delta);
    EXPECT_FLOAT_EQ(s.pdf, 1.0f);  // the only light: selection probability 1
    EXPECT_FLOAT_EQ(s.distance, 2.0f);
    EXPECT_FLOAT_EQ(s.radiance.x, 1.0f);
    EXPECT_FLOAT_EQ(s.radiance.y, 2.0f);
    EXPECT_FLOAT_EQ(s.radiance.z, 3.0f);
    EXPECT_FLOAT_EQ(s.wi.z, 1.0f);
    // Three times as far: a ninth.
    ASSERT_TRUE(sample_light(set.view(), {1, 2, -3}, 0.5f, {0.3f, 0.3f}, &s));
    EXPECT_FLOAT_EQ(s.radiance.x, 4.0f / 36.0f);
    // At the light itself nothing can be sampled (no division by zero).
    EXPECT_FALSE(sample_light(set.view(), {1, 2, 3}, 0.5f, {0.3f, 0.3f}, &s));
}

TEST(PunctualLight, SpotFalloffFollowsGltf) {
    // cos_inner = 0.9, cos_outer = 0.8: scale = 10, offset = -8, so at cos 0.85 the attenuation is
    // (8.5 - 8)^2 = 0.25; inside the inner cone 1; outside the outer cone 0.
    EXPECT_NEAR(spot_attenuation(0.85f, 0.9f, 0.8f), 0.25f, 1e-5f);
    EXPECT_NEAR(spot_attenuation(0.82f, 0.9f, 0.8f), 0.04f, 1e-5f);
    EXPECT_EQ(spot_attenuation(0.95f, 0.9f, 0.8f), 1.0f);
    EXPECT_EQ(spot_attenuation(0.7f, 0.9f, 0.8f), 0.0f);
    EXPECT_EQ(spot_attenuation(0.5f, 0.5f, 0.5f), 0.0f);  // inner == outer: a hard edge, no division by 0
    // ... whose width is 0.001 in cosine: 0.0001 inside the edge gives (0.1)^2 (float rounding of 0.5001:
    // 1e-4).
    EXPECT_NEAR(spot_attenuation(0.5001f, 0.5f, 0.5f), 0.01f, 1e-4f);

    scene::PunctualLight p;
    p.type = scene::PunctualType::Spot;
    p.position = {0, 0, 0};
    p.direction = {0, 0, -1};
    p.intensity = Rgb(8.0f);
    p.inner_cone = std::acos(0.9f);
    p.outer_cone = std::acos(0.8f);
    scene::Scene scene = one_light(p);
    LightSet set(scene);
    auto ls = set.view();
    auto at_angle = [&](float cos_theta) {  // a receiver 2 away, cos_theta off the spot axis
        float sin_theta = std::sqrt(1.0f - cos_theta * cos_theta);
        return Vec3(2.0f * sin_theta, 0.0f, -2.0f * cos_theta);
    };
    LightSample s;
    ASSERT_TRUE(sample_light(ls, at_angle(0.85f), 0.1f, {0.5f, 0.5f}, &s));
    EXPECT_NEAR(s.radiance.x, 8.0f * 0.25f / 4.0f, 1e-4f);
    EXPECT_TRUE(s.is_delta);
    EXPECT_FLOAT_EQ(s.distance, 2.0f);
    ASSERT_TRUE(sample_light(ls, at_angle(0.95f), 0.1f, {0.5f, 0.5f}, &s));
    EXPECT_NEAR(s.radiance.x, 8.0f / 4.0f, 1e-5f);
    EXPECT_FALSE(sample_light(ls, at_angle(0.7f), 0.1f, {0.5f, 0.5f}, &s));  // outside the cone: no light
    EXPECT_FALSE(sample_light(ls, {0, 0, 2}, 0.1f, {0.5f, 0.5f}, &s));       // behind the spot
}

TEST(PunctualLight, DirectionalIsIlluminanceFromMinusDirection) {
    scene::PunctualLight p;
    p.type = scene::PunctualType::Directional;
    p.direction = {0, -2, 0};  // not unit: the builder normalises it
    p.intensity = {3, 2, 1};
    scene::Scene scene = one_light(p);
    LightSet set(scene);
    LightSample s;
    ASSERT_TRUE(sample_light(set.view(), {5, 5, 5}, 0.9f, {0.1f, 0.1f}, &s));
    EXPECT_TRUE(s.is_delta);
    EXPECT_TRUE(std::isinf(s.distance));
    EXPECT_FLOAT_EQ(s.wi.y, 1.0f);
    EXPECT_FLOAT_EQ(s.radiance.x, 3.0f);
    EXPECT_FLOAT_EQ(s.radiance.z, 1.0f);
    EXPECT_FLOAT_EQ(s.pdf, 1.0f);
}

}  // namespace
}  // namespace npt::lights
