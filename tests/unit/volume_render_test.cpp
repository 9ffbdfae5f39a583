// Volumes through the whole path tracer, from a scene with a raw grid file on disk: seen directly, in a
// mirror, from inside, and as a shadow caster. Constant fields and delta lights make every expected value a
// closed form, and the estimator deterministic (each march of a constant medium is exact), so the tolerance
// is float rounding: 1e-3 relative.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "core/image_io.h"
#include "render/scene_data.h"
#include "scene/scene.h"
#include "scene_builders.h"
#include "test_support.h"

namespace npt::render {
namespace {

// An 8^3 raw instant-ngp grid of constant sigma_ngp and sRGB colour.
std::filesystem::path write_constant_raw(const std::filesystem::path& dir, float sigma_ngp, Vec3 srgb) {
    auto path = dir / "8x8x8_constant.bin";
    std::ofstream f(path, std::ios::binary);
    for (int i = 0; i < 8 * 8 * 8; ++i) {
        float v[4] = {srgb.x, srgb.y, srgb.z, sigma_ngp};
        f.write(reinterpret_cast<const char*>(v), sizeof v);
    }
    return path;
}

// A cube [-1, 1]^3 scaled by `half` and moved to `centre`: side 2 * half.
scene::VolumeInstance cube(Vec3 centre, float half, const std::string& extras,
                           const std::filesystem::path& dir) {
    scene::VolumeInstance v;
    v.name = "volume";
    v.local_to_world = Mat4::translation(centre.x, centre.y, centre.z) * Mat4::scale(half, half, half);
    v.extras_json = extras;
    v.declared_in = dir / "scene.gltf";
    return v;
}

Rgb trace_volume(const scene::Scene& s, Ray ray) { return test::trace_one_path(s, ray); }

void expect_volume_rgb(Rgb got, Vec3 expected, const char* what) {
    for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(got[k], expected[k], 1e-3 * std::max(expected[k], 1e-3f)) << what << " ch " << k;
}

struct VolumeFixture {
    std::filesystem::path dir = test::temp_dir();
    // sigma_ngp 3 over a cube of side 0.5 (half 0.25): sigma per world unit 3 / 0.5 = 6.
    const float sigma = 6.0f;
    const Vec3 srgb{0.8f, 0.5f, 0.2f};
    Vec3 linear() const { return {srgb_to_linear(srgb.x), srgb_to_linear(srgb.y), srgb_to_linear(srgb.z)}; }
    std::string extras(bool shadows = true) const {
        return std::string(R"({"volume": {"file": "8x8x8_constant.bin", "casts_shadows": )") +
               (shadows ? "true" : "false") + "}}";
    }
    VolumeFixture() { write_constant_raw(dir, 3.0f, srgb); }
};

TEST(VolumeRender, SeenDirectlyOverABackground) {
    VolumeFixture f;
    scene::Scene s;
    s.source = f.dir / "scene.gltf";
    s.environment.color = Vec3(0.1f, 0.2f, 0.3f);
    s.volumes = {cube({0, 0, 0}, 0.25f, f.extras(), f.dir)};
    // Along z through the centre: d = 0.5.
    Rgb l = trace_volume(s, {{0, 0, 3}, {0, 0, -1}});
    float t = std::exp(-f.sigma * 0.5f);
    expect_volume_rgb(l, f.linear() * (1 - t) + s.environment.color * t, "direct");
    // From inside (the camera in the volume): d = 0.25 - (-0.1) = 0.35 towards +x... going -z from z = 0.1.
    l = trace_volume(s, {{0.05f, 0.0f, 0.1f}, {0, 0, -1}});
    t = std::exp(-f.sigma * 0.35f);
    expect_volume_rgb(l, f.linear() * (1 - t) + s.environment.color * t, "inside");
}

TEST(VolumeRender, SeenInAMirrorAndClippedByASurfaceInside) {
    VolumeFixture f;
    scene::Scene s;
    s.source = f.dir / "scene.gltf";
    scene::Material mirror;
    mirror.base_color = Rgb(1.0f);  // Schlick F = 1 at every angle: a perfect mirror
    mirror.metallic = 1.0f;
    mirror.roughness = 0.0f;
    scene::Material black;  // an opaque black wall
    black.base_color = Rgb(0.0f);
    black.metallic = 0.0f;
    black.specular = 0.0f;
    s.materials = {mirror, black};
    // Mirror plane x = 1 facing -x; the volume at the origin; the camera looks at the mirror from (0.5, 0,
    // 3).
    s.meshes = {test::make_quad({1, -5, 5}, {0, 10, 0}, {0, 0, -10}, 0)};
    s.volumes = {cube({0, 0, 0}, 0.25f, f.extras(), f.dir)};
    Vec3 eye{0.5f, 0.0f, 3.0f};
    // Aim at the mirror point whose reflection passes through the volume centre: the reflected ray leaves the
    // mirror towards (0,0,0) as if from the mirrored eye (1.5, 0, 3).
    Vec3 mirrored_eye{1.5f, 0.0f, 3.0f};
    float tm = 0.5f / 1.5f;  // x goes 1.5 -> 0 along the segment; hits x = 1 at tm
    Vec3 on_mirror = mirrored_eye + (Vec3(0.0f) - mirrored_eye) * tm;
    Ray ray{eye, normalize(on_mirror - eye)};
    // Through the cube along the reflected direction (a chord through the centre): exact length by slabs.
    Vec3 dir = normalize(Vec3(0.0f) - mirrored_eye);
    float tx = 0.25f / std::fabs(dir.x), tz = 0.25f / std::fabs(dir.z);
    float d = 2.0f * std::min(tx, tz);
    float t = std::exp(-f.sigma * d);
    expect_volume_rgb(trace_volume(s, ray), f.linear() * (1 - t), "mirror");

    // A black wall through the cube's centre plane z = 0 (facing +z): only the front half glows.
    s.meshes = {test::make_quad({-5, -5, 0}, {10, 0, 0}, {0, 10, 0}, 1)};
    s.materials = {black, black};
    t = std::exp(-f.sigma * 0.25f);
    expect_volume_rgb(trace_volume(s, {{0.05f, 0.05f, 3}, {0, 0, -1}}), f.linear() * (1 - t), "clipped");
}

TEST(VolumeRender, CastsShadowsOnlyWhenAsked) {
    VolumeFixture f;
    scene::Scene s;
    s.source = f.dir / "scene.gltf";
    scene::Material floor;
    floor.base_color = Rgb(0.5f);
    floor.metallic = 0.0f;
    floor.specular = 0.0f;
    s.materials = {floor};
    s.meshes = {test::make_quad({-5, 0, 5}, {10, 0, 0}, {0, 0, -10}, 0)};
    scene::PunctualLight sun;
    sun.type = scene::PunctualType::Directional;
    sun.direction = {0, -1, 0};
    sun.intensity = Rgb(2.0f);
    s.lights = {sun};
    // A pure absorber (black colour) above the floor, so nothing but the shadow changes the floor.
    write_constant_raw(f.dir, 3.0f, Vec3(0.0f));
    s.volumes = {cube({0, 1, 0}, 0.25f, f.extras(true), f.dir)};
    // Look straight down at the floor point under the volume, from beside it (the eye ray misses the cube).
    Vec3 p{0.1f, 0.0f, 0.05f}, eye{2.0f, 2.0f, 0.05f};
    Ray ray{eye, normalize(p - eye)};
    const float lit = 0.5f / 3.14159265f * 2.0f;  // albedo / pi * E * cos(0)
    expect_volume_rgb(trace_volume(s, ray), Vec3(lit * std::exp(-f.sigma * 0.5f)), "shadowed");
    s.volumes = {cube({0, 1, 0}, 0.25f, f.extras(false), f.dir)};
    expect_volume_rgb(trace_volume(s, ray), Vec3(lit), "casts_shadows false");
}

TEST(VolumeRender, BadVolumeDescriptionsAreOneLineErrors) {
    VolumeFixture f;
    scene::Scene s;
    s.source = f.dir / "scene.gltf";
    s.volumes = {cube({0, 0, 0}, 0.25f, "", f.dir)};
    test::expect_error_message([&] { SceneData d(s, 4, 4); }, {"scene.gltf", "node 'volume'", "extras"});
    s.volumes = {cube({0, 0, 0}, 0.25f, R"({"volume": {"file": "missing.vdb"}})", f.dir)};
    test::expect_error_message([&] { SceneData d(s, 4, 4); }, {"missing.vdb"});
    s.volumes = {cube({0, 0, 0}, 0.25f, R"({"volume": {"file": "model.npt"}})", f.dir)};
    test::expect_error_message([&] { SceneData d(s, 4, 4); }, {"node 'volume'", "model.npt"});
    s.volumes = {cube({0, 0, 0}, 0.25f, R"({"volume": {"file": "m.npt", "crop": {"min": [0, 0]}}})", f.dir)};
    test::expect_error_message([&] { SceneData d(s, 4, 4); }, {"node 'volume'", "crop.min", "3 numbers"});
}

}  // namespace
}  // namespace npt::render
