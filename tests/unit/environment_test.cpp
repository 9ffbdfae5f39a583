// Tests of the environment light: the equirect direction convention and rotation, importance sampling against
// uniform sphere sampling of the same map, pdf consistency and normalisation, and the constant-colour
// furnace.
#include "lights/environment.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "core/sampling.h"
#include "lights/light.h"
#include "lights/light_set.h"

namespace npt::lights {
namespace {

// A w x h map: a dim sky gradient with a small very bright patch (a "sun") at texels [40, 44) x [9, 12).
scene::Texture sun_map(int w, int h) {
    scene::Texture t;
    t.width = w;
    t.height = h;
    t.rgba.resize(size_t(w) * size_t(h) * 4);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float* p = &t.rgba[(size_t(y) * size_t(w) + size_t(x)) * 4];
            bool sun = x >= 40 && x < 44 && y >= 9 && y < 12;
            p[0] = sun ? 400.0f : 0.2f + 0.3f * float(y) / float(h);
            p[1] = sun ? 380.0f : 0.3f;
            p[2] = sun ? 300.0f : 0.5f - 0.3f * float(y) / float(h);
            p[3] = 1.0f;
        }
    return t;
}

scene::Scene env_scene(float rotation) {
    scene::Scene s;
    s.textures.push_back(sun_map(64, 32));
    s.environment.texture = 0;
    s.environment.strength = 1.5f;
    s.environment.rotation_y = rotation;
    return s;
}

struct Estimate {
    double mean, std_error;
};

template <typename F>
Estimate estimate(int n, F&& f) {
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
        double v = f();
        sum += v;
        sum2 += v * v;
    }
    double mean = sum / n;
    return {mean, std::sqrt(std::fmax(sum2 / n - mean * mean, 0.0) / n)};
}

TEST(Environment, DirectionConventionAndRotation) {
    // u = 0.5 + atan2(x, -z) / 2pi, v = acos(y) / pi: -Z is the image centre, +X is u = 0.75, up is v = 0.
    Vec2 uv = equirect_uv({0, 0, -1});
    EXPECT_NEAR(uv.x, 0.5f, 1e-6f);
    EXPECT_NEAR(uv.y, 0.5f, 1e-6f);
    EXPECT_NEAR(equirect_uv({1, 0, 0}).x, 0.75f, 1e-6f);
    EXPECT_NEAR(equirect_uv({-1, 0, 0}).x, 0.25f, 1e-6f);
    EXPECT_NEAR(equirect_uv({0, 1, 0}).y, 0.0f, 1e-6f);
    EXPECT_NEAR(equirect_uv({0, -1, 0}).y, 1.0f, 1e-6f);
    for (Vec2 q : {Vec2(0.1f, 0.2f), Vec2(0.6f, 0.7f), Vec2(0.9f, 0.45f)}) {
        float st;
        Vec2 back = equirect_uv(equirect_direction(q, &st));
        EXPECT_NEAR(back.x, q.x, 1e-5f);
        EXPECT_NEAR(back.y, q.y, 1e-5f);
    }

    scene::Scene plain = env_scene(0.0f), turned = env_scene(0.5f * k_pi);
    LightSet a(plain), b(turned);
    // The sun's centre texel (42, 10.5) -> map direction; turned by +90 degrees about +Y it is found at
    // R_y(90) d = (d.z, d.y, -d.x).
    float st;
    Vec3 d = equirect_direction({42.0f / 64.0f, 10.5f / 32.0f}, &st);
    Rgb in_plain = environment_radiance(a.view().environment, d);
    Rgb in_turned = environment_radiance(b.view().environment, {d.z, d.y, -d.x});
    EXPECT_NEAR(in_plain.x, 400.0f * 1.5f,
                1e-2f);  // texel centre: bilinear returns the texel, times strength
    EXPECT_NEAR(in_turned.x, in_plain.x, 1e-2f);
    EXPECT_LT(environment_radiance(b.view().environment, d).x, 10.0f);  // the sun moved away from d
}

TEST(Environment, ImportanceSamplingMatchesUniformSampling) {
    scene::Scene scene = env_scene(0.7f);
    LightSet set(scene);
    auto ls = set.view();
    ASSERT_EQ(set.size(), 1u);
    ASSERT_EQ(ls.environment_light, 0);
    Vec3 n = normalize(Vec3(0.3f, 0.8f, 0.2f));

    Pcg32 rng(17, 3);
    int failures = 0;
    Estimate is = estimate(100000, [&] {
        LightSample s;
        if (!sample_light(ls, Vec3(0.0f), rng.next_float(), rng.next_2d(), &s)) {
            ++failures;
            return 0.0;
        }
        return double(luminance(s.radiance)) * std::fmax(0.0, double(dot(n, s.wi))) / double(s.pdf);
    });
    Pcg32 rng2(18, 4);
    Estimate uni = estimate(1000000, [&] {
        Vec3 w = sample_uniform_sphere(rng2.next_2d());
        return double(luminance(environment_radiance(ls.environment, w))) *
               std::fmax(0.0, double(dot(n, w))) / double(uniform_sphere_pdf());
    });
    EXPECT_EQ(failures, 0);
    // Both are unbiased estimates of the same integral: they must agree within 4 standard errors of their
    // difference. Importance sampling must also be far less noisy on a map with a sun.
    double se = std::sqrt(is.std_error * is.std_error + uni.std_error * uni.std_error);
    EXPECT_NEAR(is.mean, uni.mean, 4.0 * se)
        << "IS " << is.mean << " +- " << is.std_error << ", uniform " << uni.mean << " +- " << uni.std_error;
    EXPECT_LT(is.std_error * std::sqrt(100000.0), 0.5 * uni.std_error * std::sqrt(1000000.0));

    // The uniform estimate is too noisy to expose a bias of a few percent, so also compare with midpoint
    // quadrature over the map's (u, v) square (sub-texel step; kinks of the bilinear filter fall on cell
    // borders). Halving the step changes it by 2e-5 relative; 1e-3 relative is allowed for it.
    double quad = 0;
    const int qu = 64 * 8, qv = 32 * 8;
    for (int j = 0; j < qv; ++j)
        for (int i = 0; i < qu; ++i) {
            float sin_theta;
            Vec3 d = environment_to_world(ls.environment,
                                          equirect_direction({(i + 0.5f) / qu, (j + 0.5f) / qv}, &sin_theta));
            quad += double(luminance(environment_radiance(ls.environment, d))) *
                    std::fmax(0.0, double(dot(n, d))) * 2.0 * double(k_pi) * double(k_pi) * double(sin_theta);
        }
    quad /= double(qu) * double(qv);
    EXPECT_NEAR(is.mean, quad, 4.0 * is.std_error + 1e-3 * quad)
        << "IS " << is.mean << " +- " << is.std_error;
}

TEST(Environment, PdfMatchesSampleAndIntegratesToOne) {
    scene::Scene scene = env_scene(-1.1f);
    LightSet set(scene);
    auto ls = set.view();
    Pcg32 rng(5, 5);
    int mismatches = 0;
    const int n = 50000;
    for (int i = 0; i < n; ++i) {
        LightSample s;
        ASSERT_TRUE(sample_light(ls, Vec3(1.0f, 2.0f, 3.0f), rng.next_float(), rng.next_2d(), &s));
        EXPECT_FALSE(s.is_delta);
        EXPECT_TRUE(std::isinf(s.distance));
        float pdf = environment_light_pdf(ls, s.wi);
        // The direction is rebuilt from uv through trigonometry and a rotation, so a sample on a texel border
        // can land in the neighbour on the way back; allow that for at most 0.1% of the samples.
        if (std::fabs(pdf - s.pdf) > 1e-3f * s.pdf) ++mismatches;
        Rgb r = environment_radiance(ls.environment, s.wi);
        ASSERT_NEAR(r.x, s.radiance.x, 1e-4f * (1.0f + r.x));
    }
    EXPECT_LE(mismatches, n / 1000);
    // E_uniform[pdf / (1 / 4pi)] = integral of pdf over the sphere = 1, within 4 standard errors.
    Pcg32 rng2(6, 6);
    Estimate total = estimate(400000, [&] {
        return double(environment_light_pdf(ls, sample_uniform_sphere(rng2.next_2d()))) / double(k_inv_4pi);
    });
    EXPECT_NEAR(total.mean, 1.0, 4.0 * total.std_error) << "std error " << total.std_error;
}

TEST(Environment, ConstantRadianceGivesPiL) {
    scene::Scene scene;
    scene.environment.color = {0.5f, 1.0f, 2.0f};
    scene.environment.strength = 2.0f;
    LightSet set(scene);
    auto ls = set.view();
    ASSERT_EQ(set.size(), 1u);
    Vec3 n = normalize(Vec3(-0.4f, 0.1f, 0.9f));
    Pcg32 rng(8, 8);
    Estimate e = estimate(200000, [&] {
        LightSample s;
        if (!sample_light(ls, Vec3(0.0f), rng.next_float(), rng.next_2d(), &s)) return 0.0;
        EXPECT_NEAR(environment_light_pdf(ls, s.wi), s.pdf, 1e-6f);
        return double(s.radiance.z) * std::fmax(0.0, double(dot(n, s.wi))) / double(s.pdf);
    });
    // Irradiance of a uniform sky of radiance L = 2 * 2: pi L, within 4 standard errors.
    EXPECT_NEAR(e.mean, double(k_pi) * 4.0, 4.0 * e.std_error) << "std error " << e.std_error;
    // A black environment is no light at all.
    scene::Scene dark;
    LightSet none(dark);
    EXPECT_EQ(none.size(), 0u);
    EXPECT_EQ(none.view().environment_light, -1);
    EXPECT_EQ(environment_light_pdf(none.view(), {0, 1, 0}), 0.0f);
    EXPECT_TRUE(is_black(environment_radiance(none.view().environment, {0, 1, 0})));
}

}  // namespace
}  // namespace npt::lights
