// The images of `nerfpt eval`: ground truth composited on the background from the stored bytes, the heat
// map's ramp and gain, the strip's panel order, and that encoded values survive write_png byte for byte.
#include "nerf/eval_images.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/image_io.h"
#include "test_support.h"

namespace npt::nerf {
namespace {

// Two 3x2 frames whose bytes differ per frame, pixel and channel; alpha runs over 0, 51, ..., 255.
Dataset small_dataset() {
    Dataset d;
    d.width = 3;
    d.height = 2;
    d.cameras.resize(2);
    d.names = {"a", "b"};
    d.rgba.resize(2 * d.image_bytes());
    for (size_t f = 0; f < 2; ++f)
        for (size_t p = 0; p < 6; ++p) {
            uint8_t* px = d.rgba.data() + f * d.image_bytes() + 4 * p;
            for (size_t c = 0; c < 3; ++c) px[c] = uint8_t(f * 100 + p * 20 + c * 7);
            px[3] = uint8_t(51 * p);
        }
    return d;
}

TEST(EvalImages, GroundTruthCompositesStoredValues) {
    const Dataset d = small_dataset();
    const Rgb bg(1.0f, 0.5f, 0.0f);
    const Image img = ground_truth_image(d, 1, bg);
    ASSERT_EQ(img.width, 3);
    ASSERT_EQ(img.height, 2);
    ASSERT_EQ(img.channels, 3);
    for (size_t p = 0; p < 6; ++p) {
        const double a = 51.0 * double(p) / 255.0;
        const double bgc[3] = {1.0, 0.5, 0.0};
        for (size_t c = 0; c < 3; ++c) {
            const double rgb = double(100 + p * 20 + c * 7) / 255.0;
            EXPECT_NEAR(img.pixels[3 * p + c], rgb * a + bgc[c] * (1 - a), 1e-6) << p << " " << c;
        }
    }
    // Alpha 0 is the background exactly, alpha 255 the stored value exactly.
    EXPECT_EQ(img.pixels[0], 1.0f);
    EXPECT_EQ(img.pixels[15 + 1], float(100 + 5 * 20 + 7) / 255.0f);
    test::expect_error_message([&] { ground_truth_image(d, 2, bg); }, {"frame 2", "2 frames"});
}

// The photo's ground truth over one background equals the same photo's ground truth over another once the
// first background is replaced by the plate: over_plate is exact compositing algebra, alpha 0 the plate
// alone.
TEST(EvalImages, OverPlateReplacesTheBackground) {
    const Dataset d = small_dataset();
    const Rgb white(1.0f), grey(0.25f, 0.5f, 0.75f);
    Image render = ground_truth_image(d, 1, white), with_alpha(3, 2, 4);
    for (size_t p = 0; p < 6; ++p) {
        for (size_t c = 0; c < 3; ++c) with_alpha.pixels[4 * p + c] = render.pixels[3 * p + c];
        with_alpha.pixels[4 * p + 3] = float(51 * p) / 255.0f;
    }
    Image plate(3, 2, 3);
    for (size_t p = 0; p < 6; ++p)
        for (size_t c = 0; c < 3; ++c) plate.pixels[3 * p + c] = grey[int(c)];
    const Image over = over_plate(with_alpha, white, plate), expect = ground_truth_image(d, 1, grey);
    ASSERT_EQ(over.channels, 3);
    for (size_t i = 0; i < over.pixels.size(); ++i) EXPECT_NEAR(over.pixels[i], expect.pixels[i], 1e-6) << i;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(over.pixels[size_t(c)], grey[c], 1e-6);  // alpha 0: the plate
    test::expect_error_message([&] { over_plate(render, white, plate); }, {"no alpha"});
    test::expect_error_message([&] { over_plate(with_alpha, white, Image(2, 2, 3)); }, {"differ in size"});
}

TEST(EvalImages, HeatMapRampAndGain) {
    Image a(4, 1, 3), b(4, 1, 3);
    // Mean |diff| 0, 1/12, 1/6, 1/4: with gain 4 the ramp positions 0, 1/3, 2/3, 1.
    const float diffs[4] = {0.0f, 1.0f / 12, 1.0f / 6, 0.25f};
    for (int x = 0; x < 4; ++x)
        for (int c = 0; c < 3; ++c) b.at(x, 0)[c] = (c == 1 ? -1.0f : 1.0f) * diffs[x];
    const Image h = error_heat_map(a, b, 4.0f);
    const float expect[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {1, 1, 1}};
    for (int x = 0; x < 4; ++x)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(h.at(x, 0)[c], expect[x][c], 1e-5f) << x << " " << c;
    b.at(0, 0)[0] = NAN;
    EXPECT_EQ(error_heat_map(a, b, 4.0f).at(0, 0)[2], 1.0f);
    test::expect_error_message([&] { error_heat_map(a, Image(3, 1, 3), 4.0f); }, {"4x1 vs 3x1"});
}

TEST(EvalImages, StripPanelsInOrder) {
    Image gt(2, 2, 3), render(2, 2, 4);
    std::fill(gt.pixels.begin(), gt.pixels.end(), 0.25f);
    std::fill(render.pixels.begin(), render.pixels.end(), 0.5f);
    const Image s = comparison_strip(gt, render);
    ASSERT_EQ(s.width, 6);
    ASSERT_EQ(s.height, 2);
    EXPECT_EQ(s.at(1, 1)[0], 0.25f);
    EXPECT_EQ(s.at(2, 0)[2], 0.5f);
    EXPECT_EQ(s.at(4, 1)[0], 1.0f);  // |0.25 - 0.5| x 4 = 1: the top of the ramp
}

TEST(EvalImages, EncodedValuesSurvivePng) {
    // Every 8-bit level: written through encoded_to_linear + write_png and read back undecoded, each byte
    // must come back as it was (the curves are inverse to ~1e-6, far inside half a level).
    Image img(256, 1, 3);
    for (int x = 0; x < 256; ++x)
        for (int c = 0; c < 3; ++c) img.at(x, 0)[c] = float(x) / 255.0f;
    const auto path = test::temp_dir() / "levels.png";
    write_png(path, encoded_to_linear(img));
    const Image back = read_image(path, /*srgb=*/false);
    ASSERT_EQ(back.width, 256);
    for (int x = 0; x < 256; ++x)
        for (int c = 0; c < 3; ++c) EXPECT_EQ(std::lround(back.at(x, 0)[c] * 255.0f), x) << x;
}

}  // namespace
}  // namespace npt::nerf
