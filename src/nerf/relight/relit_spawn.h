// Where the rays of a relit scattering event start: the renderer (media/relit_free_flight.h,
// render/relit_event.h) and the relight trainer must agree on it, or the trained albedo compensates for a
// self-shadowing that the renderer does not have (or the reverse). Model space, NPT_HD.
#pragma once

#include "core/platform.h"
#include "core/vec.h"

namespace npt::nerf {

// The offset, in NeRF march steps (MarchParams::min_step = sqrt(3) / max_steps, 1.7e-3 model units by default),
// along the facing normal. Why 4: a free-flight event lies where the optical depth along the ray crosses an
// Exp(1) draw, i.e. inside the density's skin (P(depth > 3) = 5%). A trained NeRF's skin rises from empty to
// opaque over one to two march steps (training marches at this step, and its finest hash cells are a third of
// a step), so an event sits at most ~2 steps inside it; an origin that stays inside sees the rest of the skin
// on every shadow ray and darkens itself by up to e^-3. Four steps clear twice that, while staying well below
// the scale of geometry a NeRF resolves (about 0.7% of the model's unit box), so contact shadows and thin parts
// keep their shadows.
constexpr float k_relit_spawn_offset_steps = 4.0f;

// The offset in model units for a model marched with min_step.
NPT_HD NPT_INLINE float relit_spawn_offset(float min_step) { return k_relit_spawn_offset_steps * min_step; }

// The normal turned to face the direction the event is seen from: `d` is the ray's direction (model space),
// so the normal faces -d. Ties (a normal in the ray's plane) keep the normal as it is.
NPT_HD NPT_INLINE Vec3 relit_facing_normal(Vec3 n, Vec3 d) { return dot(n, d) > 0.0f ? -n : n; }

// The spawn point of the event at p: moved by the offset along the facing normal (model space).
NPT_HD NPT_INLINE Vec3 relit_spawn_point(Vec3 p, Vec3 facing_normal, float min_step) {
    return p + facing_normal * relit_spawn_offset(min_step);
}

}  // namespace npt::nerf
