// Per-image exposure in NeRF training (training.exposure_per_image): the Adam step on the gains, the trainer
// recovering a known exposure change, and the gains' trip through a checkpoint.
#include <gtest/gtest.h>

#include <cmath>

#include "nerf/image_exposure.h"
#include "nerf/model_file.h"
#include "nerf/trainer.h"
#include "nerf_test_scene.h"
#include "test_support.h"

namespace npt::nerf {
namespace {

TEST(ImageExposure, StepMovesAgainstTheGradientKeepsTheMeanAndSkipsUnseenImages) {
    ExposureState s = make_exposure_state(3);
    exposure_step(s, {Rgb(1.0f), Rgb(0.0f), Rgb(-2.0f, 0.5f, -1.0f)}, 0.01f);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(s.log_gain[0][c] + s.log_gain[1][c] + s.log_gain[2][c], 0.0f, 1e-7f);
        EXPECT_LT(s.log_gain[0][c], s.log_gain[1][c]);  // a positive gradient lowers the gain
        EXPECT_EQ(s.m[1][c], 0.0f);                     // no ray of image 1: its moments stay
        EXPECT_EQ(s.v[1][c], 0.0f);
    }
    EXPECT_GT(s.log_gain[2].x, s.log_gain[1].x);
    EXPECT_LT(s.log_gain[2].y, s.log_gain[1].y);
    // Adam's first step moves each seen parameter by the learning rate (before the mean is taken out).
    EXPECT_NEAR(s.log_gain[0].x - s.log_gain[1].x, -0.01f, 1e-5f);
    test::expect_error_message([&] { exposure_step(s, {Rgb(NAN), Rgb(0.0f), Rgb(0.0f)}, 0.01f); },
                               {"exposure", "image 0", "NaN"});
    test::expect_error_message([&] { exposure_step(s, {Rgb(0.0f)}, 0.01f); }, {"exposure", "1 images", "3"});
}

// Sphere views over an opaque grey backdrop (a capture's photos are opaque), every other view darker by 30% in
// all channels, as a phone's auto-exposure does between frames. The trainer's gains must find that ratio: the
// geometric mean gain of the dark views over that of the bright ones, 0.7 within 0.05 per channel (the gains
// also absorb the views' own colour error, a few percent at 32 px after these steps).
Dataset spheres_with_exposure_steps(float dark) {
    Dataset ds = test::make_sphere_scene({.views = 20, .size = 32, .view_seed = 1});
    for (size_t v = 0; v < ds.cameras.size(); ++v) {
        uint8_t* px = ds.rgba.data() + v * ds.image_bytes();
        const float gain = v % 2 ? dark : 1.0f;
        for (size_t p = 0; p < size_t(ds.width) * ds.height; ++p) {
            const float a = px[4 * p + 3] / 255.0f;
            for (int k = 0; k < 3; ++k)
                px[4 * p + k] = uint8_t(std::lround(gain * (px[4 * p + k] * a + 128.0f * (1.0f - a))));
            px[4 * p + 3] = 255;
        }
    }
    return ds;
}

TEST(ImageExposure, TrainerRecoversAKnownExposureChange) {
    const Dataset train = spheres_with_exposure_steps(0.7f);
    NerfConfig cfg = test::small_sphere_config();
    cfg.training.exposure_per_image = true;
    cfg.training.exposure_learning_rate = 0.01f;  // faster than the default: 800 steps, not thousands
    NerfModel model = create_model(cfg, train.aabb_scale, ngp_world_to_model(train.scale, train.offset));
    Trainer trainer(model, train);
    for (int i = 0; i < 800; ++i) trainer.step();
    const ExposureState& e = model.training->exposure;
    ASSERT_EQ(e.log_gain.size(), train.cameras.size());
    Rgb dark(0.0f), bright(0.0f);
    for (size_t v = 0; v < e.log_gain.size(); ++v) (v % 2 ? dark : bright) += e.log_gain[v];
    const float pairs = float(e.log_gain.size() / 2);
    for (int c = 0; c < 3; ++c) {
        const float ratio = std::exp((dark[c] - bright[c]) / pairs);
        std::printf("channel %d: dark / bright gain %.3f (truth 0.7)\n", c, ratio);
        EXPECT_NEAR(ratio, 0.7f, 0.05f) << "channel " << c;
    }

    // The gains travel with the training state and come back as they were.
    trainer.sync_model();
    const auto dir = test::temp_dir();
    save_model(dir / "m.npt", model, true);
    const NerfModel back = load_model(dir / "m.npt");
    ASSERT_TRUE(back.training);
    EXPECT_EQ(back.training->exposure.step, e.step);
    ASSERT_EQ(back.training->exposure.log_gain.size(), e.log_gain.size());
    for (size_t v = 0; v < e.log_gain.size(); ++v)
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(back.training->exposure.log_gain[v][c], e.log_gain[v][c]);
            EXPECT_EQ(back.training->exposure.v[v][c], e.v[v][c]);
        }
}

TEST(ImageExposure, OffLeavesNoState) {
    const Dataset train = test::make_sphere_scene({.views = 4, .size = 16, .view_seed = 1});
    NerfModel model = create_model(test::small_sphere_config(), train.aabb_scale,
                                   ngp_world_to_model(train.scale, train.offset));
    Trainer trainer(model, train);
    trainer.step();
    EXPECT_TRUE(model.training->exposure.empty());
}

}  // namespace
}  // namespace npt::nerf
