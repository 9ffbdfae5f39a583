// Training rays where the subject is (subject_focus.h, train_pixel.h): each image's rectangle holds every
// pixel whose camera ray (generate_pixel_ray, the trainer's own) crosses the box, and little more; a camera
// inside the box's reach gets its whole image; the draws put the configured share of rays inside the
// rectangles and, without a focus, are the draws of before, bit for bit.
#include "nerf/subject_focus.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "nerf/train_pixel.h"
#include "nerf_test_scene.h"

namespace npt::nerf {
namespace {

std::array<Vec3, 8> box_corners(Vec3 lo, Vec3 hi) {
    std::array<Vec3, 8> c;
    for (int i = 0; i < 8; ++i)
        c[size_t(i)] = Vec3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
    return c;
}

// Slab test: does the ray cross the axis-aligned box in front of its origin?
bool crosses(const Ray& r, Vec3 lo, Vec3 hi) {
    float t0 = 0.0f, t1 = 1e30f;
    for (int a = 0; a < 3; ++a) {
        const float o = r.o[a], d = r.d[a];
        if (std::fabs(d) < 1e-12f) {
            if (o < lo[a] || o > hi[a]) return false;
            continue;
        }
        float ta = (lo[a] - o) / d, tb = (hi[a] - o) / d;
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    }
    return t0 <= t1;
}

bool inside(const PixelRect& r, float x, float y) { return x >= r.x0 && x <= r.x1 && y >= r.y0 && y <= r.y1; }

TEST(SubjectFocus, EachRectangleHoldsThePixelsThatSeeTheBoxAndLittleMore) {
    const Dataset ds = test::make_sphere_scene({.views = 6, .size = 64, .view_seed = 3});
    const Vec3 lo(-0.3f, -0.2f, -0.1f), hi(0.4f, 0.25f, 0.5f);
    const float margin = 2.0f;
    const std::vector<PixelRect> rects = subject_rects(ds.cameras, box_corners(lo, hi), margin);
    ASSERT_EQ(rects.size(), ds.cameras.size());
    for (size_t i = 0; i < ds.cameras.size(); ++i) {
        const PixelRect& r = rects[i];
        int seeing = 0, seeing_outside = 0, far_inside = 0, far_inside_seeing = 0;
        for (int y = 0; y < ds.height; ++y)
            for (int x = 0; x < ds.width; ++x) {
                const float px = x + 0.5f, py = y + 0.5f;
                const bool sees = crosses(generate_pixel_ray(ds.cameras[i], px, py), lo, hi);
                seeing += sees;
                if (sees && !inside(r, px, py)) ++seeing_outside;
                // Deep inside the rectangle's rim: the box's outline is convex, so the rectangle is tight
                // where its edges touch it; a rectangle much too large would have a wide band of misses.
                const bool deep = inside(
                    PixelRect{r.x0 + margin + 1, r.y0 + margin + 1, r.x1 - margin - 1, r.y1 - margin - 1}, px,
                    py);
                far_inside += deep;
                far_inside_seeing += deep && sees;
            }
        EXPECT_GT(seeing, 50) << "view " << i;
        EXPECT_EQ(seeing_outside, 0) << "view " << i;
        // The projection of a box fills at least half of its bounding rectangle (a hexagon at worst).
        EXPECT_GT(far_inside_seeing, far_inside / 2) << "view " << i;
        EXPECT_LT((r.x1 - r.x0) * (r.y1 - r.y0), 0.9f * ds.width * ds.height) << "view " << i;
    }
}

TEST(SubjectFocus, ACameraWithTheBoxBehindItOrOffTheImageGetsTheWholeImage) {
    const Dataset ds = test::make_sphere_scene({.views = 3, .size = 32, .view_seed = 5});
    const PixelRect whole{0.0f, 0.0f, float(ds.width), float(ds.height)};
    auto same = [](const PixelRect& a, const PixelRect& b) {
        return a.x0 == b.x0 && a.y0 == b.y0 && a.x1 == b.x1 && a.y1 == b.y1;
    };
    // A box around every camera: corners behind each of them.
    for (const PixelRect& r : subject_rects(ds.cameras, box_corners(Vec3(-9.0f), Vec3(9.0f)), 1.0f))
        EXPECT_TRUE(same(r, whole));
    // A box far to the side of what the cameras see (they look at the origin from distance 4).
    const Vec3 far = ds.cameras[0].camera_to_world.transform_vector(Vec3(1.0f, 0.0f, 0.0f)) * 40.0f;
    const std::vector<PixelRect> off =
        subject_rects(ds.cameras, box_corners(far - Vec3(0.1f), far + Vec3(0.1f)), 1.0f);
    EXPECT_TRUE(same(off[0], whole));
}

TEST(SubjectFocus, TheConfiguredShareOfRaysLandsInTheRectangles) {
    const int w = 80, h = 60;
    const uint32_t images = 4;
    const std::vector<PixelRect> rects = {
        {10, 10, 30, 20}, {0, 0, 80, 60}, {50.5f, 30.25f, 79.5f, 59.0f}, {40, 0, 41, 60}};
    double expected_in = 0;
    const float fraction = 0.6f;
    for (const PixelRect& r : rects)
        expected_in += fraction + (1.0f - fraction) * (r.x1 - r.x0) * (r.y1 - r.y0) / float(w * h);
    expected_in /= images;
    const int n = 40000;
    int in = 0;
    for (uint32_t ray = 0; ray < uint32_t(n); ++ray) {
        const uint64_t seed = 0x1234 + ray / 1000;
        const TrainPixel plain = draw_train_pixel(seed, ray, images, w, h, true, 0.0f);
        const TrainPixel none = draw_train_pixel(seed, ray, images, w, h, true, 0.0f, {rects.data(), 0.0f});
        const TrainPixel focused =
            draw_train_pixel(seed, ray, images, w, h, true, 0.0f, {rects.data(), fraction});
        // Without a focus (or a share of 0) the draws are those of before; the focus moves the position only.
        ASSERT_EQ(none.px, plain.px);
        ASSERT_EQ(none.py, plain.py);
        ASSERT_EQ(focused.image, plain.image);
        ASSERT_EQ(focused.jitter, plain.jitter);
        ASSERT_EQ(focused.background.x, plain.background.x);
        ASSERT_TRUE(focused.px >= 0.0f && focused.px < float(w) && focused.py >= 0.0f &&
                    focused.py < float(h));
        in += inside(rects[focused.image], focused.px, focused.py);
    }
    // Binomial: 4 standard deviations of the share over n draws.
    const double sigma = std::sqrt(expected_in * (1.0 - expected_in) / n);
    EXPECT_NEAR(double(in) / n, expected_in, 4.0 * sigma);
}

}  // namespace
}  // namespace npt::nerf
