// Mask IoU, DAVIS boundary F and leak on hand-made masks whose values are counted by hand in the comments,
// and reading masks from PNG (alpha, grey, opaque alpha, bad files).
#include "core/mask_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include "core/error.h"
#include "core/image.h"
#include "core/image_io.h"
#include "test_support.h"

namespace npt {
namespace {

namespace fs = std::filesystem;

// A w x h mask with the s x s square whose top-left pixel is (x0, y0) set.
Mask square(int w, int h, int x0, int y0, int s) {
    Mask m{w, h, std::vector<uint8_t>(size_t(w) * size_t(h), 0)};
    for (int y = y0; y < y0 + s; ++y)
        for (int x = x0; x < x0 + s; ++x) m.on[size_t(y) * size_t(w) + size_t(x)] = 1;
    return m;
}

size_t count(const Mask& m) {
    size_t n = 0;
    for (uint8_t v : m.on) n += v;
    return n;
}

bool at(const Mask& m, int x, int y) { return m.on[size_t(y) * size_t(m.width) + size_t(x)] != 0; }

TEST(MaskMetrics, IouOfShiftedSquares) {
    // 4x4 squares one pixel apart along x: 12 pixels shared, 20 in the union.
    EXPECT_DOUBLE_EQ(mask_iou(square(10, 10, 2, 2, 4), square(10, 10, 3, 2, 4)), 12.0 / 20.0);
    EXPECT_DOUBLE_EQ(mask_iou(square(10, 10, 2, 2, 4), square(10, 10, 2, 2, 4)), 1.0);
    EXPECT_DOUBLE_EQ(mask_iou(square(10, 10, 0, 0, 2), square(10, 10, 5, 5, 2)), 0.0);
    EXPECT_DOUBLE_EQ(mask_iou(square(10, 10, 0, 0, 0), square(10, 10, 0, 0, 0)), 1.0);  // both empty
    EXPECT_THROW(mask_iou(square(10, 10, 0, 0, 2), square(10, 11, 0, 0, 2)), Error);
}

TEST(MaskMetrics, ThresholdIsStrictlyAboveOneHalf) {
    const Coverage c{3, 1, {0.5f, 0.5001f, 1.0f}};
    const Mask m = threshold_coverage(c);
    EXPECT_EQ(m.on, (std::vector<uint8_t>{0, 1, 1}));
}

TEST(MaskMetrics, BoundaryOfASquareIsTheRingAroundItsLowerRightEdges) {
    // seg2bmap marks the square's right column and bottom row (7 pixels for s = 4) and, outside, the column
    // left of it and the row above it (5 + 5 - 1 = 9): the ring of the 5x5 box from (2,2) to (6,6), 16
    // pixels.
    const Mask b = mask_boundary(square(10, 10, 3, 3, 4));
    EXPECT_EQ(count(b), 16u);
    for (int y = 0; y < 10; ++y)
        for (int x = 0; x < 10; ++x) {
            const bool in_box = x >= 2 && x <= 6 && y >= 2 && y <= 6;
            const bool inner = x >= 3 && x <= 5 && y >= 3 && y <= 5;
            EXPECT_EQ(at(b, x, y), in_box && !inner) << x << "," << y;
        }
    // The image border is not a boundary: a full mask has none, a square in a corner only its inner edges.
    EXPECT_EQ(count(mask_boundary(square(6, 6, 0, 0, 6))), 0u);
    // 3x3 square at the top-left: its right column and bottom row (5); the outside half of the ring would
    // lie left of and above it, off the image.
    EXPECT_EQ(count(mask_boundary(square(6, 6, 0, 0, 3))), 5u);
}

TEST(MaskMetrics, DilationIsTheEuclideanDisk) {
    // One pixel dilated by 5: the integer points with dx^2 + dy^2 <= 25, 81 of them.
    const Mask d = dilate_mask(square(21, 21, 10, 10, 1), 5.0);
    EXPECT_EQ(count(d), 81u);
    EXPECT_TRUE(at(d, 13, 14));   // 3^2 + 4^2 = 25
    EXPECT_FALSE(at(d, 14, 14));  // 32
    EXPECT_TRUE(at(d, 15, 10));
    EXPECT_FALSE(at(d, 16, 10));
    EXPECT_EQ(count(dilate_mask(square(7, 7, 0, 0, 0), 3.0)), 0u);  // nothing to dilate
}

TEST(MaskMetrics, DilationMatchesBruteForceOnRandomMasks) {
    uint32_t state = 12345;
    const auto next = [&] { return (state = state * 1664525u + 1013904223u) >> 8; };
    for (int trial = 0; trial < 6; ++trial) {
        const int w = 17 + trial, h = 23 - trial;
        Mask m{w, h, std::vector<uint8_t>(size_t(w) * size_t(h))};
        for (uint8_t& v : m.on) v = next() % 29 == 0 ? 1 : 0;
        const double r = 0.5 + trial * 0.9;
        const Mask d = dilate_mask(m, r);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                bool near = false;
                for (int qy = 0; qy < h; ++qy)
                    for (int qx = 0; qx < w; ++qx)
                        near = near || (at(m, qx, qy) && (qx - x) * (qx - x) + (qy - y) * (qy - y) <= r * r);
                ASSERT_EQ(at(d, x, y), near) << "trial " << trial << " at " << x << "," << y;
            }
    }
}

TEST(MaskMetrics, BoundaryFOfAShiftedSquare) {
    // 10x10 squares at (10,10) and (13,10) in 40x40: boundary rings of the 11x11 boxes x 9..19 and 12..22
    // (y 9..19), 40 pixels each.
    const Mask pred = square(40, 40, 10, 10, 10), truth = square(40, 40, 13, 10, 10);
    // Tolerance 1: top and bottom rows match for x 11..19 (9 + 9), the right column x = 19 only at y 10 and
    // 18 (next to the truth's rows), the left column never: 20 of 40. The same for the truth: P = R = F =
    // 0.5.
    BoundaryScore s = boundary_f(pred, truth, 1);
    EXPECT_DOUBLE_EQ(s.precision, 0.5);
    EXPECT_DOUBLE_EQ(s.recall, 0.5);
    EXPECT_DOUBLE_EQ(s.f, 0.5);
    // Tolerance 2: rows x 10..19 (10 + 10), right column y 10, 11, 17, 18 (4): 24 of 40.
    s = boundary_f(pred, truth, 2);
    EXPECT_DOUBLE_EQ(s.precision, 0.6);
    EXPECT_DOUBLE_EQ(s.recall, 0.6);
    EXPECT_DOUBLE_EQ(s.f, 0.6);
    // Tolerance 3 covers the shift: every boundary pixel is matched.
    EXPECT_DOUBLE_EQ(boundary_f(pred, truth, 3).f, 1.0);
    // Unequal P and R: a 4x4 square in the truth's top-left corner, ring x 12..16, y 9..13 (16 pixels).
    // Within 1 px of the truth's ring (x = 12, y = 9 here): its top row (5), left column (3), (13,13) and
    // (16,10) beside those, and (12,13): 11 of 16. The truth's: its top row x 12..17 and left column y 9..14,
    // 6 + 6 - 1 shared corner = 11 of 40.
    s = boundary_f(square(40, 40, 13, 10, 4), truth, 1);
    EXPECT_DOUBLE_EQ(s.precision, 11.0 / 16.0);
    EXPECT_DOUBLE_EQ(s.recall, 11.0 / 40.0);
    EXPECT_DOUBLE_EQ(s.f, 2 * (11.0 / 16) * (11.0 / 40) / (11.0 / 16 + 11.0 / 40));
}

TEST(MaskMetrics, BoundaryFWithoutABoundary) {
    const Mask empty = square(8, 8, 0, 0, 0), some = square(8, 8, 2, 2, 3);
    EXPECT_DOUBLE_EQ(boundary_f(empty, empty, 1).f, 1.0);
    BoundaryScore s = boundary_f(empty, some, 1);  // nothing predicted
    EXPECT_DOUBLE_EQ(s.precision, 1.0);
    EXPECT_DOUBLE_EQ(s.recall, 0.0);
    EXPECT_DOUBLE_EQ(s.f, 0.0);
    s = boundary_f(some, empty, 1);  // nothing there
    EXPECT_DOUBLE_EQ(s.precision, 0.0);
    EXPECT_DOUBLE_EQ(s.recall, 1.0);
}

TEST(MaskMetrics, ToleranceIsDavis) {
    EXPECT_EQ(boundary_tolerance(540, 960), 9);  // ceil(0.008 * 1101.4)
    EXPECT_EQ(boundary_tolerance(32, 32), 1);
    EXPECT_EQ(boundary_tolerance(854, 480), 8);  // DAVIS 480p: ceil(7.84)
}

TEST(MaskMetrics, LeakIsTheMeanCoverageFarFromTheObject) {
    // A 4x4 object at (8,8) in 20x20. Within 5 px of it: 16 + 4 sides x 4 x 5 + 4 corners x 15 (points with
    // dx, dy >= 1 and dx^2 + dy^2 <= 25) = 156 pixels; 244 are farther.
    const Mask truth = square(20, 20, 8, 8, 4);
    EXPECT_EQ(count(dilate_mask(truth, 5)), 156u);
    Coverage c{20, 20, std::vector<float>(400, 0.0f)};
    const auto px = [&](int x, int y) -> float& { return c.values[size_t(y) * 20 + size_t(x)]; };
    for (int y = 8; y < 12; ++y)
        for (int x = 8; x < 12; ++x) px(x, y) = 1.0f;  // the object itself: no leak
    px(16, 9) = 1.0f;  // 5 px right of the object's column x = 11: inside the margin
    px(17, 9) = 0.5f;  // 6 px: counts
    px(0, 0) = 1.0f;   // a floater in the corner
    EXPECT_DOUBLE_EQ(mask_leak(c, truth), 1.5 / 244.0);
    px(0, 0) = 7.0f;  // clamped to 1
    EXPECT_DOUBLE_EQ(mask_leak(c, truth), 1.5 / 244.0);

    const MaskScores s = score_mask(c, truth);
    // Thresholded prediction: the object + (16,9) + (17,9)? 0.5 is not > 0.5 + (0,0): 18 pixels, 16 shared.
    EXPECT_DOUBLE_EQ(s.iou, 16.0 / 18.0);
    EXPECT_DOUBLE_EQ(s.leak, 1.5 / 244.0);
    EXPECT_GT(s.boundary.f, 0.5);
    EXPECT_LT(s.boundary.f, 1.0);
}

TEST(MaskMetrics, CoverageInsideIsTheMeanOverTheObjectOnly) {
    const Mask truth = square(10, 10, 2, 2, 4);         // 16 object pixels
    Coverage c{10, 10, std::vector<float>(100, 1.0f)};  // covered everywhere: outside does not count
    const auto px = [&](int x, int y) -> float& { return c.values[size_t(y) * 10 + size_t(x)]; };
    EXPECT_DOUBLE_EQ(mask_coverage_inside(c, truth), 1.0);
    px(2, 2) = 0.0f;
    px(3, 2) = 0.5f;
    px(4, 2) = 3.0f;                                     // clamped to 1
    px(5, 2) = std::numeric_limits<float>::quiet_NaN();  // counts as uncovered
    EXPECT_DOUBLE_EQ(mask_coverage_inside(c, truth), 13.5 / 16.0);
    EXPECT_TRUE(std::isnan(mask_coverage_inside(c, Mask{10, 10, std::vector<uint8_t>(100, 0)})));
    EXPECT_THROW(mask_coverage_inside(c, Mask{9, 10, std::vector<uint8_t>(90, 1)}), Error);
}

TEST(MaskMetrics, ReadsAlphaOrGrey) {
    const fs::path dir = test::temp_dir();
    Image rgba(4, 2, 4);  // premultiplied: colour 0, alpha = the mask
    rgba.at(1, 0)[3] = 1.0f;
    rgba.at(2, 1)[3] = 1.0f;
    write_png_premultiplied(dir / "alpha.png", rgba);
    Coverage c = read_coverage(dir / "alpha.png");
    ASSERT_EQ(c.width, 4);
    ASSERT_EQ(c.height, 2);
    EXPECT_EQ(threshold_coverage(c).on, (std::vector<uint8_t>{0, 1, 0, 0, 0, 0, 1, 0}));

    Image grey(4, 2, 4);  // opaque everywhere: the alpha channel carries nothing, grey is the mask
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) grey.at(x, y)[3] = 1.0f;
    for (int c2 = 0; c2 < 3; ++c2) grey.at(3, 0)[c2] = grey.at(0, 1)[c2] = 1.0f;
    write_png_premultiplied(dir / "opaque.png", grey);
    write_png(dir / "grey.png", grey);  // RGB, no alpha
    for (const char* name : {"opaque.png", "grey.png"}) {
        c = read_coverage(dir / name);
        EXPECT_EQ(threshold_coverage(c).on, (std::vector<uint8_t>{0, 0, 0, 1, 1, 0, 0, 0})) << name;
    }

    // A 4x2 mask shrunk by 2: box means of 2x2 blocks, the trailing odd column dropped.
    const Coverage big{5, 2, {1, 1, 0, 1, 1, 1, 0, 0, 0, 1}};
    const Coverage small = downscale_coverage(big, 2);
    ASSERT_EQ(small.width, 2);
    ASSERT_EQ(small.height, 1);
    EXPECT_FLOAT_EQ(small.values[0], 0.75f);
    EXPECT_FLOAT_EQ(small.values[1], 0.25f);

    EXPECT_THROW(read_coverage(dir / "missing.png"), Error);
    test::write_file(dir / "bad.png", "not a png");
    try {
        read_coverage(dir / "bad.png");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("bad.png"), std::string::npos) << e.what();
    }
}

// The object's PSNR counts only the masked pixels: a 2x2 square whose pixels differ by 0.1 in every channel
// (MSE 0.01, 20 dB) inside an image that differs by 0.5 everywhere else.
TEST(MaskMetrics, PsnrInsideTheMaskIgnoresEverythingElse) {
    Image a(6, 5, 4), b(6, 5, 4);
    const Mask m = square(6, 5, 1, 2, 2);
    for (size_t p = 0; p < 30; ++p)
        for (int c = 0; c < 3; ++c) {
            a.pixels[p * 4 + c] = 0.3f;
            b.pixels[p * 4 + c] = m.on[p] ? 0.4f : 0.8f;
        }
    EXPECT_NEAR(psnr_inside(a, b, m), 20.0, 1e-5);
    EXPECT_TRUE(std::isinf(psnr_inside(a, a, m)));
    test::expect_error_message([&] { psnr_inside(a, b, square(6, 5, 0, 0, 0)); }, {"covers no pixel"});
    test::expect_error_message([&] { psnr_inside(a, Image(5, 5, 4), m); }, {"differ in size"});
}

}  // namespace
}  // namespace npt
