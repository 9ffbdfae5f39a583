// Training end to end on a scene small enough for CI: three shaded spheres at 32x32 from 20 views, checked on
// 5 views it never saw. A wrong gradient anywhere (encoding, MLPs, compositing) or a broken occupancy grid
// keeps the held-out PSNR near what a constant colour gets; the bounds below sit far above that.
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <chrono>
#include <cmath>

#include "nerf/render_view.h"
#include "nerf/trainer.h"
#include "nerf_test_scene.h"
#include "test_support.h"

namespace npt::nerf {
namespace {

NerfConfig small_config() { return test::small_sphere_config(); }

// Mean PSNR over the views of `test`, composited on white as the evaluation convention says.
double held_out_psnr(const NerfModel& model, const Dataset& test) {
    double sum = 0;
    for (size_t v = 0; v < test.cameras.size(); ++v) {
        const Image img = render_view(model, test.cameras[v], {});
        double se = 0;
        const uint8_t* gt = test.image(v);
        for (size_t p = 0; p < size_t(test.width) * test.height; ++p) {
            const float a = gt[4 * p + 3] / 255.0f;
            for (int k = 0; k < 3; ++k) {
                const double target = gt[4 * p + k] / 255.0 * a + (1.0 - a);
                se += std::pow(img.pixels[4 * p + k] - target, 2);
            }
        }
        sum += psnr_from_mse(se / (3.0 * test.width * test.height));
    }
    return sum / double(test.cameras.size());
}

// The best a model that ignores geometry can do: every pixel the mean target colour.
double constant_colour_psnr(const Dataset& test) {
    double mean[3] = {0, 0, 0};
    const size_t n = test.cameras.size() * test.width * test.height;
    auto target = [&](size_t p, int k) {
        const float a = test.rgba[4 * p + 3] / 255.0f;
        return test.rgba[4 * p + k] / 255.0 * a + (1.0 - a);
    };
    for (size_t p = 0; p < n; ++p)
        for (int k = 0; k < 3; ++k) mean[k] += target(p, k) / double(n);
    double se = 0;
    for (size_t p = 0; p < n; ++p)
        for (int k = 0; k < 3; ++k) se += std::pow(target(p, k) - mean[k], 2);
    return psnr_from_mse(se / (3.0 * n));
}

TEST(NerfTraining, OverfitsSpheresAndGeneralisesToHeldOutViews) {
    const Dataset train = test::make_sphere_scene({.views = 20, .size = 32, .view_seed = 1});
    const Dataset test = test::make_sphere_scene({.views = 5, .size = 32, .view_seed = 2});
    NerfModel model = create_model(small_config(), train.aabb_scale,
                                   ngp_world_to_model(train.scale, train.offset));
    Trainer trainer(model, train);
    const auto t0 = std::chrono::steady_clock::now();
    double first_loss = 0, last_loss = 0;
    for (int i = 0; i < 400; ++i) {
        const StepStats s = trainer.step();
        ASSERT_TRUE(std::isfinite(s.loss)) << "step " << i;
        if (i == 0) first_loss = s.loss;
        last_loss = s.loss;
    }
    trainer.sync_model();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double psnr = held_out_psnr(model, test);
    const double baseline = constant_colour_psnr(test);
    RecordProperty("held_out_psnr", std::to_string(psnr));
    std::printf("400 steps in %.1f s: loss %.4f -> %.4f, held-out PSNR %.2f dB (constant colour %.2f dB), "
                "occupied %.1f%%\n",
                seconds, first_loss, last_loss, psnr, baseline, 100.0 * model.occupancy.occupied_fraction());
    EXPECT_LT(last_loss, 0.2 * first_loss);
    EXPECT_GT(psnr, baseline + 10.0);
    EXPECT_GT(psnr, 24.0);
    // The spheres fill a small part of the cube: the grid must have found the empty space.
    EXPECT_LT(model.occupancy.occupied_fraction(), 0.5);
}

TEST(NerfTraining, SameSeedSameModelWhateverTheThreadCount) {
    const Dataset train = test::make_sphere_scene({.views = 6, .size = 16, .view_seed = 3});
    auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        NerfModel m = create_model(small_config(), 1.0f, ngp_world_to_model(train.scale, train.offset));
        Trainer t(m, train);
        for (int i = 0; i < 20; ++i) t.step();
        t.sync_model();
        return m;
    };
    const NerfModel a = run(1), b = run(2);
    ASSERT_EQ(a.params.size(), b.params.size());
    size_t diff = 0;
    for (size_t i = 0; i < a.params.size(); ++i) diff += a.params[i] != b.params[i];
    EXPECT_EQ(diff, 0u);
    EXPECT_EQ(a.occupancy.density(), b.occupancy.density());
}

TEST(NerfTraining, RejectsAnEmptyDataSet) {
    const Dataset empty;
    NerfModel m = create_model(small_config(), 1.0f, ngp_world_to_model(0.33f, Vec3(0.5f)));
    test::expect_error_message([&] { Trainer t(m, empty); }, {"no frames"});
}

}  // namespace
}  // namespace npt::nerf
