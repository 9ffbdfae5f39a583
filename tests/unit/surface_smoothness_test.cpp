// The surface-smoothness loss (surface_smoothness.h) and its grouped ray draws (train_pixel.h): zero on a plane
// seen at an angle, positive on a bump, letting go of depth edges, an exact gradient with respect to every
// sample's density (against central differences in double precision of the same formulas), and the trainer
// still learning the sphere scene with it on, the same model whatever the thread count.
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <cmath>
#include <vector>

#include "core/rng.h"
#include "nerf/surface_smoothness.h"
#include "nerf/train_pixel.h"
#include "nerf/trainer.h"
#include "nerf_test_scene.h"

namespace npt::nerf {
namespace {

SurfacePoint at(Vec3 p) { return SurfacePoint{p, 1.0f}; }

TEST(SurfaceSmoothness, ZeroOnAPlaneSeenAtAnAngle) {
    // Three rays from a pinhole through pixels on one line meet the plane z = 0 at collinear points whose
    // spacing is uneven (perspective): only a bend across the line may count.
    const Vec3 eye(0.1f, -0.4f, 0.7f);
    SurfacePoint s[3];
    for (int k = 0; k < 3; ++k) {
        const Vec3 d = normalize(Vec3(0.3f + 0.05f * k, 0.6f + 0.02f * k, -1.0f));
        s[k] = at(eye + d * (-eye.z / d.z));
    }
    const SmoothnessTerm t = smoothness_term(s, 1.0f, 0.2f);
    ASSERT_TRUE(t.active);
    EXPECT_LT(t.loss, 1e-9f);
}

TEST(SurfaceSmoothness, PenalisesABumpAndLetsGoOfADepthEdge) {
    auto loss_for = [](float height, float* grad) {
        SurfacePoint s[3] = {at(Vec3(0, 0, 0)), at(Vec3(0.01f, 0, height)), at(Vec3(0.02f, 0, 0))};
        const SmoothnessTerm t = smoothness_term(s, 1.0f, 0.2f);
        *grad = length(t.d_point[1]);
        return t.loss;
    };
    float g_small, g_bump, g_edge;
    const float small = loss_for(0.0001f, &g_small), bump = loss_for(0.002f, &g_bump),
                edge = loss_for(0.2f, &g_edge);
    // A bump of a tenth of the span: bend 0.2, at the scale, so loss 0.04 / 2.
    EXPECT_NEAR(bump, 0.02f, 1e-3f);
    EXPECT_GT(bump, 100.0f * small);
    // A depth edge (bend 20): the loss saturates at scale^2 and its gradient all but vanishes.
    EXPECT_LT(edge, 0.2f * 0.2f);
    EXPECT_LT(g_edge, 1e-3f * g_bump);
}

TEST(SurfaceSmoothness, SilhouetteRaysAreSkipped) {
    SurfacePoint s[3] = {at(Vec3(0, 0, 0)), at(Vec3(0.01f, 0, 0.005f)), at(Vec3(0.02f, 0, 0))};
    s[2].weighted_sum = s[2].weighted_sum * 0.3f;
    s[2].alpha = 0.3f;  // mostly transparent: not a surface
    EXPECT_FALSE(smoothness_term(s, 1.0f, 0.2f).active);
}

// The loss of three rays as a function of their densities, in double precision, by the same formulas.
double loss_in_double(const std::vector<std::vector<double>>& sigma, const std::vector<std::vector<Vec3>>& pos,
                      const std::vector<std::vector<double>>& dt, double weight, double scale) {
    double p[3][3];
    for (int k = 0; k < 3; ++k) {
        double tau = 0, sum[3] = {0, 0, 0}, alpha;
        for (size_t i = 0; i < sigma[k].size(); ++i) {
            const double w = std::exp(-tau) * -std::expm1(-sigma[k][i] * dt[k][i]);
            for (int a = 0; a < 3; ++a) sum[a] += w * pos[k][i][a];
            tau += sigma[k][i] * dt[k][i];
        }
        alpha = -std::expm1(-tau);
        for (int a = 0; a < 3; ++a) p[k][a] = sum[a] / alpha;
    }
    double d[3], second[3];
    for (int a = 0; a < 3; ++a) d[a] = p[0][a] - p[2][a];
    const double span = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    double along = 0;
    for (int a = 0; a < 3; ++a) {
        second[a] = (p[0][a] - 2 * p[1][a] + p[2][a]) / span;
        along += second[a] * d[a] / span;
    }
    double b2 = 0;
    for (int a = 0; a < 3; ++a) {
        const double b = second[a] - along * d[a] / span;
        b2 += b * b;
    }
    return weight * b2 / (1 + b2 / (scale * scale));
}

TEST(SurfaceSmoothness, GradientMatchesFiniteDifferences) {
    // Three rays crossing a bumpy shell: 24 samples each with densities that make every ray mostly opaque.
    Pcg32 rng(11, 3);
    const int n = 24;
    std::vector<std::vector<float>> sigma(3, std::vector<float>(n)), dt(3, std::vector<float>(n));
    std::vector<std::vector<Vec3>> pos(3, std::vector<Vec3>(n));
    for (int k = 0; k < 3; ++k) {
        const Vec3 o(0.02f * k, 0.0f, 1.0f), dir = normalize(Vec3(0.1f, 0.05f * k, -1.0f));
        for (int i = 0; i < n; ++i) {
            dt[k][i] = 0.004f;
            pos[k][i] = o + dir * (0.45f + 0.004f * i);
            const float shell = 0.5f + 0.004f * float(k == 1);  // the middle ray's surface is further
            const float x = (0.45f + 0.004f * i - shell) / 0.02f;
            sigma[k][i] = 60.0f * std::exp(-x * x) + 5.0f * rng.next_float();
        }
    }
    const float weight = 0.7f, scale = 0.2f;
    SurfacePoint points[3];
    for (int k = 0; k < 3; ++k) points[k] = surface_point(sigma[k].data(), pos[k].data(), dt[k].data(), n);
    const SmoothnessTerm term = smoothness_term(points, weight, scale);
    ASSERT_TRUE(term.active);
    ASSERT_GT(term.loss, 0.0f);

    std::vector<std::vector<double>> sd(3), dd(3);
    for (int k = 0; k < 3; ++k) {
        sd[k].assign(sigma[k].begin(), sigma[k].end());
        dd[k].assign(dt[k].begin(), dt[k].end());
    }
    EXPECT_NEAR(loss_in_double(sd, pos, dd, weight, scale), term.loss, 1e-3 * term.loss);
    double worst = 0, largest = 0;
    for (int k = 0; k < 3; ++k) {
        std::vector<float> grad(n, 0.0f);
        surface_point_backward_add(sigma[k].data(), pos[k].data(), dt[k].data(), n, points[k], term.d_point[k],
                                   grad.data());
        for (int i = 0; i < n; ++i) {
            const double h = 1e-4 * std::max(1.0, sd[k][i]);
            auto plus = sd, minus = sd;
            plus[k][i] += h;
            minus[k][i] -= h;
            const double fd = (loss_in_double(plus, pos, dd, weight, scale) -
                               loss_in_double(minus, pos, dd, weight, scale)) / (2 * h);
            worst = std::max(worst, std::abs(fd - grad[i]));
            largest = std::max(largest, std::abs(fd));
        }
    }
    // Float against double, over sums of 24 samples: a few 1e-4 of the largest derivative.
    EXPECT_GT(largest, 0.0);
    EXPECT_LT(worst, 5e-3 * largest) << "largest derivative " << largest;
}

TEST(SurfaceSmoothness, GroupedDrawsShareAnImageAndLieOnALine) {
    const int width = 40, height = 30;
    for (uint32_t g = 0; g < 200; ++g) {
        TrainPixel p[3];
        for (uint32_t k = 0; k < 3; ++k) p[k] = draw_train_pixel(99, 3 * g + k, 7, width, height, true, 6.0f);
        for (uint32_t k = 0; k < 3; ++k) {
            EXPECT_EQ(p[k].image, p[0].image);
            EXPECT_EQ(p[k].jitter, p[0].jitter);
            EXPECT_TRUE(p[k].px >= 0.0f && p[k].px < float(width) && p[k].py >= 0.0f && p[k].py < float(height));
        }
        const float dx0 = p[1].px - p[0].px, dy0 = p[1].py - p[0].py;
        const float dx1 = p[2].px - p[1].px, dy1 = p[2].py - p[1].py;
        const float spacing = std::hypot(dx0, dy0);
        EXPECT_GE(spacing, 1.0f - 1e-3f);
        EXPECT_LE(spacing, 6.0f + 1e-3f);
        EXPECT_NEAR(dx0, dx1, 1e-3f);
        EXPECT_NEAR(dy0, dy1, 1e-3f);
    }
    // Off, ray r draws alone from Pcg32(seed, r): image first.
    Pcg32 rng(99, 5);
    EXPECT_EQ(draw_train_pixel(99, 5, 7, width, height, true, 0.0f).image, rng.next_u32() % 7);
}

TEST(SurfaceSmoothness, TrainerLearnsWithItAndIsDeterministic) {
    const Dataset train = test::make_sphere_scene({.views = 6, .size = 24, .view_seed = 5});
    auto run = [&](int threads, double* smoothness, double* first_loss, double* last_loss) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        NerfConfig cfg = test::small_sphere_config();
        cfg.loss.surface_smoothness = 0.1f;
        NerfModel m = create_model(cfg, train.aabb_scale, ngp_world_to_model(train.scale, train.offset));
        Trainer t(m, train);
        for (int i = 0; i < 80; ++i) {
            const StepStats s = t.step();
            EXPECT_TRUE(std::isfinite(s.loss) && std::isfinite(s.smoothness));
            EXPECT_EQ(s.rays % 3, 0u);
            if (i == 0) *first_loss = s.loss;
            *last_loss = s.loss;
            *smoothness += s.smoothness;
        }
        t.sync_model();
        return m;
    };
    double smooth_a = 0, smooth_b = 0, first, last, unused;
    const NerfModel a = run(1, &smooth_a, &first, &last), b = run(2, &smooth_b, &unused, &unused);
    std::printf("loss %.4f -> %.4f, smoothness summed over the steps %.2e\n", first, last, smooth_a);
    EXPECT_LT(last, 0.5 * first);
    EXPECT_GT(smooth_a, 0.0);  // groups on the spheres' surfaces did contribute
    ASSERT_EQ(a.params.size(), b.params.size());
    size_t diff = 0;
    for (size_t i = 0; i < a.params.size(); ++i) diff += a.params[i] != b.params[i];
    EXPECT_EQ(diff, 0u);
    EXPECT_EQ(smooth_a, smooth_b);
}

}  // namespace
}  // namespace npt::nerf
