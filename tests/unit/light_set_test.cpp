// Tests of the host light-set builder: selection proportional to power (pbrt-v4 Phi formulas), the empty
// scene, which meshes emit (volumes and black materials do not) and the per-mesh offsets.
#include "lights/light_set.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/rng.h"
#include "lights/light.h"

namespace npt::lights {
namespace {

scene::Mesh one_triangle(Vec3 a, Vec3 b, Vec3 c, int material) {
    scene::Mesh m;
    m.positions = {a, b, c};
    m.indices = {0, 1, 2};
    m.material = material;
    return m;
}

TEST(LightSet, SelectionFollowsPower) {
    scene::Scene scene;
    scene::Material lit;
    lit.emission = Rgb(1.0f);
    scene.materials = {lit};
    // Triangle of area 0.5 facing +Z; the bounding box (0..1, 0..1, 0) has radius sqrt(2)/2, pi r^2 = pi/2.
    scene.meshes.push_back(one_triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0));
    scene::PunctualLight point, spot, sun;
    point.type = scene::PunctualType::Point;
    point.position = {0, 0, 5};
    point.intensity = Rgb(1.0f);
    spot.type = scene::PunctualType::Spot;
    spot.position = {0, 0, 3};
    spot.direction = {0, 0, -1};
    spot.intensity = Rgb(2.0f);
    spot.inner_cone = std::acos(0.9f);
    spot.outer_cone = std::acos(0.8f);
    sun.type = scene::PunctualType::Directional;
    sun.direction = {0, 0, -1};
    sun.intensity = Rgb(0.5f);
    scene.lights = {point, spot, sun};
    scene.environment.color = Rgb(0.1f);
    LightSet set(scene);
    auto ls = set.view();
    ASSERT_EQ(set.size(), 5u);
    EXPECT_NEAR(set.scene_radius(), std::sqrt(2.0f) / 2.0f, 1e-6f);

    // Hand-computed powers: point 4 pi I; spot 2 pi (1 - (0.9 + 0.8) / 2) I; sun pi r^2 E; triangle
    // pi A L; environment 4 pi * pi r^2 * L. Listed in the order the builder stores them.
    const double pi = k_pi;
    std::vector<double> power = {4 * pi, 2 * pi * 0.15 * 2, pi / 2 * 0.5, pi * 0.5, 4 * pi * pi / 2 * 0.1};
    double total = 0;
    for (double p : power) total += p;
    for (size_t i = 0; i < power.size(); ++i)
        EXPECT_NEAR(ls.selector.pmf(uint32_t(i)), power[i] / total, 1e-5) << "light " << i;

    // Sampling from above the triangle: every light gives a sample, told apart by its fields.
    Vec3 x(0.2f, 0.2f, 1.0f);
    Pcg32 rng(4, 4);
    const int n = 200000;
    std::vector<int> count(5, 0);
    for (int i = 0; i < n; ++i) {
        LightSample s;
        ASSERT_TRUE(sample_light(ls, x, rng.next_float(), rng.next_2d(), &s));
        int k = s.is_delta ? (std::isinf(s.distance) ? 2 : (s.distance > 3.0f ? 0 : 1))
                           : (std::isinf(s.distance) ? 4 : 3);
        if (s.is_delta) {
            EXPECT_NEAR(s.pdf, power[size_t(k)] / total, 1e-5);
        }
        ++count[size_t(k)];
    }
    for (size_t k = 0; k < power.size(); ++k) {
        double p = power[k] / total;
        // 5 standard deviations of a binomial count.
        EXPECT_NEAR(count[k], n * p, 5 * std::sqrt(n * p * (1 - p))) << "light " << k;
    }
}

TEST(LightSet, EmptySceneGivesEmptyView) {
    scene::Scene scene;
    LightSet set(scene);
    auto ls = set.view();
    EXPECT_EQ(set.size(), 0u);
    EXPECT_EQ(set.emissive_triangles(), 0u);
    EXPECT_TRUE(ls.lights.empty());
    EXPECT_TRUE(ls.selector.bins.empty());
    EXPECT_EQ(ls.environment_light, -1);
    LightSample s;
    EXPECT_FALSE(sample_light(ls, {0, 0, 0}, 0.5f, {0.5f, 0.5f}, &s));
    EXPECT_EQ(triangle_light_pdf(ls, 0, 0, {0, 0, 0}, {1, 1, 1}), 0.0f);
    EXPECT_EQ(environment_light_pdf(ls, {0, 1, 0}), 0.0f);
    // A default-constructed view (no builder at all) is just as safe.
    LightSetView blank;
    EXPECT_FALSE(sample_light(blank, {0, 0, 0}, 0.5f, {0.5f, 0.5f}, &s));
    EXPECT_EQ(triangle_light_pdf(blank, 0, 0, {0, 0, 0}, {1, 1, 1}), 0.0f);
}

TEST(LightSet, OnlyNonVolumeEmissiveMeshesEmit) {
    scene::Scene scene;
    scene::Material plain, lit, volume, black_textured;
    lit.emission = {1.0f, 0.5f, 0.25f};
    volume.emission = Rgb(5.0f);
    volume.is_volume = true;
    black_textured.emissive_texture = 0;  // a texture alone does not make a material emit (factor is 0)
    scene::Texture tex;
    tex.width = tex.height = 1;
    tex.rgba = {1, 1, 1, 1};
    scene.textures = {tex};
    scene.materials = {plain, lit, volume, black_textured};
    scene.meshes.push_back(one_triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 0));
    scene::Mesh quad;
    quad.positions = {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    quad.indices = {0, 1, 2, 0, 2, 3};
    quad.material = 1;
    scene.meshes.push_back(quad);
    scene.meshes.push_back(one_triangle({0, 0, 2}, {1, 0, 2}, {0, 1, 2}, 2));
    scene.meshes.push_back(one_triangle({0, 0, 3}, {1, 0, 3}, {0, 1, 3}, 3));
    scene.meshes.push_back(one_triangle({0, 0, 4}, {1, 0, 4}, {0, 0, 4}, 1));  // degenerate but emissive
    LightSet set(scene);
    auto ls = set.view();
    EXPECT_EQ(set.emissive_triangles(), 3u);
    EXPECT_EQ(set.size(), 3u);
    ASSERT_EQ(ls.mesh_light_offset.size, 5u);
    EXPECT_EQ(ls.mesh_light_offset[0], -1);
    EXPECT_EQ(ls.mesh_light_offset[1], 0);
    EXPECT_EQ(ls.mesh_light_offset[2], -1);
    EXPECT_EQ(ls.mesh_light_offset[3], -1);
    EXPECT_EQ(ls.mesh_light_offset[4], 2);
    EXPECT_EQ(ls.lights[1].mesh, 1u);
    EXPECT_EQ(ls.lights[1].prim, 1u);
    // The degenerate triangle keeps its slot but is never selected.
    EXPECT_EQ(ls.lights[2].area, 0.0f);
    EXPECT_EQ(ls.selector.pmf(2), 0.0f);
    EXPECT_NEAR(ls.selector.pmf(0), 0.5f, 1e-6f);
    EXPECT_EQ(triangle_light_pdf(ls, 4, 0, {0.2f, 0.2f, 5.0f}, {0.1f, 0.0f, 4.0f}), 0.0f);
    EXPECT_EQ(triangle_light_pdf(ls, 2, 0, {0.2f, 0.2f, 2.5f}, {0.2f, 0.2f, 2.0f}), 0.0f);  // volume
    // Scene radius includes every mesh, emitting or not: box (0..1, 0..1, 0..4).
    EXPECT_NEAR(set.scene_radius(), 0.5f * std::sqrt(18.0f), 1e-5f);
}

}  // namespace
}  // namespace npt::lights
