// The random draws of one training ray, shared by the CPU and GPU trainers so that both train on the same
// pixels: ray r of a step draws, from Pcg32(step seed, r), its image, its pixel position, its background
// colour (with random backgrounds) and the jitter of its march, in that order.
//
// With the surface-smoothness loss on (surface_smoothness.h) rays come in groups of three that cross one line
// of pixels: the group's rays draw from Pcg32(step seed, r / 3) (so share the image, background and jitter:
// their depth noise is correlated and cancels in the loss), then a direction and a spacing in pixels, and the
// three pixels are the centre and the centre -+ the spacing along the direction, all inside the image.
//
// With subject rectangles (SubjectFocus), a share of the rays lands inside the rectangle of its image where
// the subject is seen: the same uniform draws, mapped into the rectangle, chosen by a draw of their own
// stream so that every other draw stays what it was without the focus.
#pragma once

#include <math.h>

#include <cstdint>

#include "core/platform.h"
#include "core/rng.h"
#include "core/vec.h"

namespace npt::nerf {

constexpr uint32_t k_smoothness_group = 3;

// Where each training image sees the subject (pixel coordinates, x0 < x1, y0 < y1, inside the image), and the
// share of rays drawn there; the rest are drawn over the whole image.
struct PixelRect {
    float x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};
struct SubjectFocus {
    const PixelRect* rects = nullptr;  // one per image; null: no focus
    float fraction = 0.0f;
};

struct TrainPixel {
    uint32_t image = 0;
    float px = 0.0f, py = 0.0f;  // continuous pixel coordinates (x right, y down)
    Rgb background{1.0f};
    float jitter = 0.5f;
};

// `max_spacing` > 0: the rays come in groups (the comment at the top), spaced 1..max_spacing pixels.
NPT_HD NPT_INLINE TrainPixel draw_train_pixel(uint64_t step_seed, uint32_t ray, uint32_t images, int width,
                                              int height, bool random_background, float max_spacing,
                                              SubjectFocus focus = {}) {
    const bool grouped = max_spacing > 0.0f;
    const uint32_t stream = grouped ? ray / k_smoothness_group : ray;
    Pcg32 rng(step_seed, stream);
    TrainPixel t;
    t.image = rng.next_u32() % images;
    t.px = rng.next_float() * float(width);
    t.py = rng.next_float() * float(height);
    if (focus.rects && Pcg32(step_seed ^ 0x5ab1ec7f0c05ull, stream).next_float() < focus.fraction) {
        const PixelRect& r = focus.rects[t.image];
        t.px = r.x0 + t.px / float(width) * (r.x1 - r.x0);
        t.py = r.y0 + t.py / float(height) * (r.y1 - r.y0);
    }
    if (random_background) {
        // One draw per statement: the order of a constructor's arguments is unspecified in C++.
        t.background.x = rng.next_float();
        t.background.y = rng.next_float();
        t.background.z = rng.next_float();
    }
    t.jitter = rng.next_float();
    if (grouped) {
        const float angle = rng.next_float() * 3.14159265f;
        const float spacing = 1.0f + rng.next_float() * fmaxf(max_spacing - 1.0f, 0.0f);
        const float dx = cosf(angle) * spacing, dy = sinf(angle) * spacing;
        // The centre moved so that the three pixels lie inside the image (when it is wide enough).
        const float mx = fabsf(dx), my = fabsf(dy);
        if (float(width) > 2.0f * mx + 1.0f) t.px = fminf(fmaxf(t.px, mx), float(width) - mx - 1e-3f);
        if (float(height) > 2.0f * my + 1.0f) t.py = fminf(fmaxf(t.py, my), float(height) - my - 1e-3f);
        const float member = float(int(ray % k_smoothness_group) - 1);
        t.px = fminf(fmaxf(t.px + member * dx, 0.0f), float(width) - 1e-3f);
        t.py = fminf(fmaxf(t.py + member * dy, 0.0f), float(height) - 1e-3f);
    }
    return t;
}

}  // namespace npt::nerf
