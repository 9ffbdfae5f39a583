// Orbit cameras for `nerfpt view`: they look at the centre from the asked distance, elevation and azimuth,
// keep world +Z up in the image, have the asked horizontal field of view, and the model-derived defaults
// give NeRF-synthetic's framing (centre at the world origin, 4.0 units away).
#include "nerf/orbit_camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "test_support.h"

namespace npt::nerf {
namespace {

constexpr double k_pi = std::numbers::pi;

// Pixel coordinates of a world point, by the inverse of generate_pixel_ray's mapping.
Vec3 project(const Camera& cam, Vec3 p) {
    const Vec3 q = cam.camera_to_world.inverse().transform_point(p);
    return Vec3(cam.cx + cam.fx * q.x / -q.z, cam.cy - cam.fy * q.y / -q.z, -q.z);
}

OrbitSettings settings() {
    OrbitSettings s;
    s.centre = Vec3(1.0f, -2.0f, 0.5f);
    s.distance = 3.0;
    s.elevation_deg = 30;
    s.width = 64;
    s.height = 48;
    s.fov_deg = 50;
    return s;
}

TEST(OrbitCamera, LooksAtTheCentreFromTheOrbit) {
    const OrbitSettings s = settings();
    for (double az : {0.0, 0.7, k_pi / 2, 2.5, -1.0}) {
        const Camera cam = orbit_camera(s, az);
        const Vec3 pos = cam.camera_to_world.transform_point(Vec3(0.0f, 0.0f, 0.0f));
        const Vec3 rel = pos - s.centre;
        const double el = 30.0 * k_pi / 180.0;
        EXPECT_NEAR(length(rel), 3.0, 1e-5);
        EXPECT_NEAR(rel.z, 3.0 * std::sin(el), 1e-5);
        EXPECT_NEAR(rel.x, 3.0 * std::cos(el) * std::cos(az), 1e-5);
        EXPECT_NEAR(rel.y, 3.0 * std::cos(el) * std::sin(az), 1e-5);
        // The ray through the image centre hits the orbit centre.
        const Ray r = generate_pixel_ray(cam, 32.0f, 24.0f);
        test::expect_near(r.o + r.d * 3.0f, s.centre, 1e-5f);
        // World +Z is up in the image, and the camera frame is a rotation (no mirror, no scale).
        EXPECT_LT(project(cam, s.centre + Vec3(0.0f, 0.0f, 0.3f)).y, 24.0f);
        EXPECT_NEAR(cam.camera_to_world.determinant3(), 1.0, 1e-9);
    }
}

TEST(OrbitCamera, AzimuthTurnsCounterClockwiseSeenFromAbove) {
    // From +X looking at the centre, +Y is on the right of the image: the azimuth grows to the right.
    const Camera cam = orbit_camera(settings(), 0.0);
    EXPECT_GT(project(cam, settings().centre + Vec3(0.0f, 0.3f, 0.0f)).x, 32.0f);
}

TEST(OrbitCamera, HorizontalFieldOfView) {
    const Camera cam = orbit_camera(settings(), 1.0);
    const Ray centre = generate_pixel_ray(cam, 32.0f, 24.0f), edge = generate_pixel_ray(cam, 0.0f, 24.0f);
    EXPECT_NEAR(std::acos(dot(centre.d, edge.d)) * 180.0 / k_pi, 25.0, 1e-3);
    EXPECT_FLOAT_EQ(cam.fx, cam.fy);
}

TEST(OrbitCamera, DefaultsFromTheModel) {
    // instant-ngp's NeRF-synthetic mapping (scale 0.33, offset 0.5): the cube's centre is the world origin
    // and the default distance is NeRF-synthetic's camera radius 4.0.
    NerfModel model;
    model.world_to_model = ngp_world_to_model(0.33f, Vec3(0.5f, 0.5f, 0.5f));
    test::expect_near(model_centre_world(model), Vec3(0.0f, 0.0f, 0.0f), 1e-6f);
    EXPECT_NEAR(default_orbit_distance(model), 4.0, 1e-5);
    model.world_to_model = ngp_world_to_model(0.5f, Vec3(0.2f, 0.5f, 0.5f));
    EXPECT_NEAR(default_orbit_distance(model), 1.32 / 0.5, 1e-5);
    // The centre maps back to the cube's centre whatever the axis order of the mapping.
    test::expect_near(model.world_to_model.transform_point(model_centre_world(model)), Vec3(0.5f, 0.5f, 0.5f),
                      1e-6f);
}

TEST(OrbitCamera, BadSettings) {
    OrbitSettings s = settings();
    s.elevation_deg = 90;
    test::expect_error_message([&] { orbit_camera(s, 0); }, {"elevation"});
    s = settings();
    s.fov_deg = 0;
    test::expect_error_message([&] { orbit_camera(s, 0); }, {"field of view"});
    s = settings();
    s.distance = -1;
    test::expect_error_message([&] { orbit_camera(s, 0); }, {"distance"});
}

}  // namespace
}  // namespace npt::nerf
