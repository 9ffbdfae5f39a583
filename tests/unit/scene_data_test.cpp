// render/scene_data: the default view of a scene without a camera. It used to have zero axes, so every
// camera ray was NaN and Embree aborted (`ray.valid()`) on any OBJ and any glTF without a camera.
#include "render/scene_data.h"

#include <gtest/gtest.h>

#include <cmath>

#include "render/camera.h"
#include "render/cpu/embree_scene.h"
#include "render/renderer.h"
#include "scene/scene.h"
#include "test_support.h"

namespace npt::render {
namespace {

scene::Scene scene_of(std::vector<Vec3> positions) {
    scene::Scene s;
    s.materials.push_back(scene::Material{});
    scene::Mesh m;
    m.name = "m";
    m.positions = std::move(positions);
    for (uint32_t i = 0; i + 2 < m.positions.size(); i += 3)
        m.indices.insert(m.indices.end(), {i, i + 1, i + 2});
    s.meshes.push_back(m);
    return s;
}

void expect_valid_view(const scene::Scene& s, const char* what) {
    SCOPED_TRACE(what);
    const CameraView c = make_camera_view(s, 64, 48);
    EXPECT_TRUE(is_finite(c.position));
    EXPECT_NEAR(length(c.forward), 1.0f, 1e-6f);
    EXPECT_NEAR(length(c.right), 1.0f, 1e-6f);
    EXPECT_NEAR(length(c.up), 1.0f, 1e-6f);
    for (int j : {0, 24, 47})
        for (int i : {0, 32, 63}) {
            const Ray r = generate_camera_ray(c, i, j, Vec2(0.5f, 0.5f));
            EXPECT_TRUE(cpu::embree_accepts(r, INFINITY)) << i << "," << j;
        }
    // The scene's centre is in front of the camera, on the view axis.
    if (!s.meshes.empty() && !s.meshes[0].positions.empty()) {
        const Vec3 to = s.meshes[0].positions[0] - c.position;
        EXPECT_GT(dot(to, c.forward), 0.0f);
    }
}

TEST(DefaultView, EveryShapeOfSceneGivesAValidView) {
    expect_valid_view(scene::Scene{}, "empty");
    expect_valid_view(scene_of({{1, 2, 3}, {1, 2, 3}, {1, 2, 3}}), "a point");
    expect_valid_view(scene_of({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}), "a line");
    expect_valid_view(scene_of({{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}}), "flat");
    expect_valid_view(scene_of({{-1e16f, -1e16f, -1e16f}, {1e16f, 1e16f, 1e16f}, {0, 1e16f, 0}}), "huge");
    expect_valid_view(scene_of({{1e7f, 1e7f, 1e7f}, {1e7f + 1, 1e7f, 1e7f}, {1e7f, 1e7f + 1, 1e7f}}), "far");
    expect_valid_view(scene_of({{1e15f, 0, 0}, {1e15f, 0, 0}, {1e15f, 0, 0}}), "a far point");
}

TEST(DefaultView, ObjWithoutCameraRenders) {
    const auto path = test::temp_dir() / "tri.obj";
    test::write_file(path, "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n");
    scene::Scene s = scene::load_scene(path);
    // Something to see: a grey triangle against a white sky (white would vanish: a white furnace).
    s.environment.color = Rgb(1.0f);
    for (auto& m : s.materials) m.base_color = Rgb(0.2f);
    RenderOptions o;
    o.width = 16;
    o.height = 12;
    o.spp = 2;
    const Image img = render(s, resolve_options(s, o));
    bool dark = false, bright = false;
    for (float v : img.pixels) {
        ASSERT_TRUE(std::isfinite(v));
        dark = dark || v < 0.9f;
        bright = bright || v > 0.99f;
    }
    EXPECT_TRUE(dark && bright) << "the triangle should fill part of the default view, not all of it";
}

}  // namespace
}  // namespace npt::render
