// Tests of emissive triangles: the Monte Carlo irradiance from sample_light against the analytic polygon
// irradiance (Lambert 1760 / Arvo 1995), the front-face rule, double-sided emitters, textured emission, and
// that triangle_light_pdf reproduces the pdf of sample_light.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/rng.h"
#include "lights/light.h"
#include "lights/light_set.h"

namespace npt::lights {
namespace {

scene::Scene triangle_scene(Vec3 p0, Vec3 p1, Vec3 p2, Rgb emission, bool double_sided) {
    scene::Scene s;
    scene::Material m;
    m.emission = emission;
    m.double_sided = double_sided;
    s.materials.push_back(m);
    scene::Mesh mesh;
    mesh.positions = {p0, p1, p2};
    mesh.indices = {0, 1, 2};
    s.meshes.push_back(mesh);
    return s;
}

// Irradiance at x (normal n) from a polygon of constant radiance L lying wholly above x's tangent plane:
// E = L/2 * sum_i angle(r_i, r_i+1) * dot(n, normalize(cross(r_i, r_i+1))), with r_i unit vectors to the
// vertices (Arvo 1995, eq. 2). The sign follows the winding, hence the fabs.
double polygon_irradiance(const Vec3* v, int count, Vec3 x, Vec3 n, double radiance) {
    double sum = 0;
    for (int i = 0; i < count; ++i) {
        Vec3 a = normalize(v[i] - x), b = normalize(v[(i + 1) % count] - x);
        double angle = std::acos(std::clamp(double(dot(a, b)), -1.0, 1.0));
        sum += angle * double(dot(n, normalize(cross(a, b))));
    }
    return 0.5 * radiance * std::fabs(sum);
}

struct Estimate {
    double mean, std_error;
    int failures;
};

// E = integral of L cos over the triangle's solid angle, by light sampling; a failed sample contributes 0.
Estimate irradiance_by_light_sampling(const LightSetView& ls, Vec3 x, Vec3 n, int samples, uint64_t seed) {
    Pcg32 rng(seed, 11);
    double sum = 0, sum2 = 0;
    int failures = 0;
    for (int i = 0; i < samples; ++i) {
        LightSample s;
        double f = 0;
        float u_sel = rng.next_float();
        Vec2 u = rng.next_2d();
        if (sample_light(ls, x, u_sel, u, &s))
            f = double(s.radiance.x) * std::fmax(0.0, double(dot(n, s.wi))) / double(s.pdf);
        else
            ++failures;
        sum += f;
        sum2 += f * f;
    }
    double mean = sum / samples;
    double var = std::fmax(sum2 / samples - mean * mean, 0.0);
    return {mean, std::sqrt(var / samples), failures};
}

const Vec3 k_p0{-1.0f, -0.5f, 2.0f}, k_p1{0.2f, 1.0f, 1.8f}, k_p2{1.0f, -0.3f, 2.2f};

TEST(TriangleLight, IrradianceMatchesPolygonFormula) {
    // Winding chosen so the front face looks at the origin.
    ASSERT_LT(dot(cross(k_p1 - k_p0, k_p2 - k_p0), k_p0), 0.0f);
    scene::Scene scene = triangle_scene(k_p0, k_p1, k_p2, {2.0f, 1.0f, 0.5f}, false);
    LightSet set(scene);
    ASSERT_EQ(set.size(), 1u);
    ASSERT_EQ(set.emissive_triangles(), 1u);
    Vec3 x(0.0f), n = normalize(Vec3(0.2f, 0.1f, 1.0f));
    const Vec3 verts[3] = {k_p0, k_p1, k_p2};
    double expected = polygon_irradiance(verts, 3, x, n, 2.0);
    Estimate e = irradiance_by_light_sampling(set.view(), x, n, 100000, 5);
    EXPECT_EQ(e.failures, 0);
    // 4 standard errors of the estimator: a correct sampler fails about once in 16000 runs; a missing
    // d^2 / cos factor or a wrong area is off by far more than that.
    EXPECT_NEAR(e.mean, expected, 4.0 * e.std_error) << "std error " << e.std_error;
    EXPECT_GT(expected, 0.05);  // the configuration is not trivially dark
}

TEST(TriangleLight, BackFaceIsDarkDoubleSidedEmitsBothWays) {
    // Seen from z = 4 the triangle shows its back face (its winding normal points towards the origin).
    Vec3 behind(0.1f, 0.0f, 4.0f), n_behind = normalize(Vec3(0.0f, 0.1f, -1.0f));
    {
        scene::Scene scene = triangle_scene(k_p0, k_p1, k_p2, Rgb(1.0f), false);
        LightSet set(scene);
        auto ls = set.view();
        Pcg32 rng(9, 9);
        for (int i = 0; i < 1000; ++i) {
            LightSample s;
            EXPECT_FALSE(sample_light(ls, behind, rng.next_float(), rng.next_2d(), &s));
        }
        Vec3 wo_back = normalize(behind - k_p0), wo_front = normalize(-k_p0);
        EXPECT_TRUE(is_black(triangle_emission(ls, ls.lights[0], {0.3f, 0.3f}, wo_back)));
        EXPECT_FALSE(is_black(triangle_emission(ls, ls.lights[0], {0.3f, 0.3f}, wo_front)));
        EXPECT_EQ(triangle_light_pdf(ls, 0, 0, behind, (k_p0 + k_p1 + k_p2) / 3.0f), 0.0f);
    }
    {
        scene::Scene scene = triangle_scene(k_p0, k_p1, k_p2, Rgb(1.0f), true);
        LightSet set(scene);
        const Vec3 verts[3] = {k_p0, k_p1, k_p2};
        for (Vec3 x : {behind, Vec3(0.0f)}) {
            Vec3 n = x.z > 1.0f ? n_behind : normalize(Vec3(0.2f, 0.1f, 1.0f));
            double expected = polygon_irradiance(verts, 3, x, n, 1.0);
            Estimate e = irradiance_by_light_sampling(set.view(), x, n, 50000, 6);
            EXPECT_EQ(e.failures, 0);
            // 4 standard errors, as above.
            EXPECT_NEAR(e.mean, expected, 4.0 * e.std_error) << "from z = " << x.z;
        }
        // A double-sided emitter has twice the power of a single-sided one (it is selected accordingly).
        scene::Scene single_scene = triangle_scene(k_p0, k_p1, k_p2, Rgb(1.0f), false);
        LightSet single(single_scene);
        EXPECT_NEAR(set.powers()[0], 2.0 * single.powers()[0], 1e-9 * single.powers()[0]);
    }
}

TEST(TriangleLight, PdfMatchesSampledPdf) {
    // A two-triangle quad plus a point light, so the selection probability is not 1.
    scene::Scene scene;
    scene::Material dark, lit;
    lit.emission = {3.0f, 3.0f, 3.0f};
    scene.materials = {dark, lit};
    scene::Mesh floor_mesh;
    floor_mesh.positions = {{-5, 0, -5}, {5, 0, -5}, {5, 0, 5}};
    floor_mesh.indices = {0, 1, 2};
    floor_mesh.material = 0;
    scene::Mesh quad;  // y = 2, facing down (-Y): front faces the origin
    quad.positions = {{-1, 2, -1}, {1, 2, -1}, {1, 2, 1}, {-1, 2, 1}};
    quad.indices = {0, 1, 2, 0, 2, 3};
    quad.material = 1;
    scene.meshes = {floor_mesh, quad};
    scene::PunctualLight point;
    point.position = {0, 3, 0};
    point.intensity = Rgb(5.0f);
    scene.lights.push_back(point);
    LightSet set(scene);
    auto ls = set.view();
    ASSERT_EQ(set.size(), 3u);
    ASSERT_EQ(ls.mesh_light_offset[0], -1);
    ASSERT_EQ(ls.mesh_light_offset[1], 1);

    Vec3 x(0.3f, 0.0f, -0.2f);
    Pcg32 rng(21, 1);
    int triangle_samples = 0;
    for (int i = 0; i < 20000; ++i) {
        LightSample s;
        if (!sample_light(ls, x, rng.next_float(), rng.next_2d(), &s) || s.is_delta) continue;
        ++triangle_samples;
        Vec3 p = x + s.wi * s.distance;
        // Triangle 0 is the half with z <= x (below the diagonal from (-1,-1) to (1,1)), triangle 1 the rest.
        uint32_t prim = p.z <= p.x ? 0u : 1u;
        float pdf = triangle_light_pdf(ls, 1, prim, x, p);
        // Float rounding of the point reconstruction only: relative 1e-4.
        ASSERT_NEAR(pdf, s.pdf, 1e-4f * s.pdf) << "sample " << i;
        EXPECT_EQ(triangle_light_pdf(ls, 0, prim, x, p), 0.0f);  // a non-emitting mesh
    }
    EXPECT_GT(triangle_samples, 1000);
    EXPECT_EQ(triangle_light_pdf(ls, 1, 2, x, {0, 2, 0}), 0.0f);  // prim out of range
    EXPECT_EQ(triangle_light_pdf(ls, 7, 0, x, {0, 2, 0}), 0.0f);  // mesh out of range
}

TEST(TriangleLight, TexturedEmissionMultipliesTexture) {
    scene::Scene scene = triangle_scene({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2.0f, 4.0f, 1.0f}, false);
    scene::Texture tex;  // 2 x 1: left half red-ish, right half blue-ish
    tex.width = 2;
    tex.height = 1;
    tex.rgba = {1.0f, 0.5f, 0.0f, 1.0f, 0.0f, 0.5f, 1.0f, 1.0f};
    scene.textures.push_back(tex);
    scene.materials[0].emissive_texture = 0;
    scene.meshes[0].uvs = {{0.25f, 0.5f}, {0.75f, 0.5f}, {0.25f, 0.5f}};
    LightSet set(scene);
    auto ls = set.view();
    const Light& l = ls.lights[0];
    Vec3 up(0, 0, 1);
    // At vertex 0 (bary 0, 0) uv = (0.25, 0.5): the centre of the left texel, so exactly texel 0.
    Rgb e0 = triangle_emission(ls, l, {0.0f, 0.0f}, up);
    EXPECT_NEAR(e0.x, 2.0f, 1e-5f);
    EXPECT_NEAR(e0.y, 2.0f, 1e-5f);
    EXPECT_NEAR(e0.z, 0.0f, 1e-5f);
    // At vertex 1 uv = (0.75, 0.5): the right texel.
    Rgb e1 = triangle_emission(ls, l, {1.0f, 0.0f}, up);
    EXPECT_NEAR(e1.x, 0.0f, 1e-5f);
    EXPECT_NEAR(e1.y, 2.0f, 1e-5f);
    EXPECT_NEAR(e1.z, 1.0f, 1e-5f);
    // Power uses the mean texture colour (0.5, 0.5, 0.5): luminance(1, 2, 0.5) * area 0.5 * pi.
    EXPECT_NEAR(set.powers()[0], double(luminance({1.0f, 2.0f, 0.5f})) * 0.5 * k_pi, 1e-5);
}

}  // namespace
}  // namespace npt::lights
