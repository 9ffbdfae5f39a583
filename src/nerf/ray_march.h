// Ray marching through the occupancy grid (instant-ngp's scheme): steps of dt = clamp(t * cone_angle,
// sqrt(3)/max_steps, max_step) along a model-space ray, inside the model's aabb, skipping unoccupied cells
// to the next cell boundary of their cascade. NPT_HD: used by training, rendering and the GPU.
#pragma once

#include <math.h>

#include "core/platform.h"
#include "core/vec.h"
#include "nerf/occupancy_view.h"

namespace npt::nerf {

struct MarchParams {
    Vec3 aabb_min{0, 0, 0};  // model-space box the field lives in: 0.5 -+ aabb_scale / 2
    Vec3 aabb_max{1, 1, 1};
    float min_step = 1.7320508f / 1024.0f;
    float max_step = 1.7320508f * 128.0f / 128.0f;  // sqrt(3) * 2^(cascades-1) / resolution
    float cone_angle = 0.0f;
    int max_samples = 1024;
    float t_max = INFINITY;  // samples stop here too (a surface in front of the far side of the box)
};

struct MarchSample {
    Vec3 position;  // model space
    float t;        // distance along the (unit-direction) ray
    float dt;       // the step this sample stands for
};

NPT_HD NPT_INLINE float march_step(const MarchParams& mp, float t) {
    return clampf(t * mp.cone_angle, mp.min_step, mp.max_step);
}

// Entry and exit distances of the ray in the aabb, clipped to t >= 0; false when it misses (also for
// non-finite input, and for a zero direction, whose exit would be infinite).
NPT_HD inline bool march_bounds(const MarchParams& mp, const Ray& ray, float* t_near, float* t_far) {
    float lo = 0.0f;
    float hi = INFINITY;
    for (int a = 0; a < 3; ++a) {
        const float o = ray.o[a];
        const float d = ray.d[a];
        const float bmin = mp.aabb_min[a];
        const float bmax = mp.aabb_max[a];
        if (!isfinite(o) || !isfinite(d) || !isfinite(bmin) || !isfinite(bmax)) return false;
        if (d == 0.0f) {
            // Parallel to this slab: 0 * inf would be NaN, so decide by the origin alone.
            if (o < bmin || o > bmax) return false;
            continue;
        }
        const float inv = 1.0f / d;
        const float t0 = (bmin - o) * inv;
        const float t1 = (bmax - o) * inv;
        lo = fmaxf(lo, fminf(t0, t1));
        hi = fminf(hi, fmaxf(t0, t1));
    }
    if (!(lo <= hi) || !isfinite(hi)) return false;
    *t_near = lo;
    *t_far = hi;
    return true;
}

// The cascade whose occupancy a step of dt at p tests (instant-ngp's mip_from_dt): the finest one whose cells
// are at least dt long, so that a step cannot jump over a whole cell it did not test, or the cascade of the
// position if that is coarser.
NPT_HD NPT_INLINE int march_cascade(const OccupancyGridView& grid, Vec3 p, float dt) {
    if (grid.cascades == 1) return 0;
    int exponent = 0;
    // dt * R = m 2^e with m in [0.5, 1): the cell size 2^c / R reaches dt at c = e, or at e - 1 when dt * R
    // is exactly 2^(e-1).
    const float mantissa = frexpf(dt * float(grid.resolution), &exponent);
    if (mantissa == 0.5f) --exponent;
    const int from_dt = exponent < 0 ? 0 : (exponent > grid.cascades - 1 ? grid.cascades - 1 : exponent);
    const int from_pos = grid.cascade_of(p);
    return from_dt > from_pos ? from_dt : from_pos;
}

// Distance along the ray from p to the exit of p's cell on a lattice of cells of side `cell` (a power of two
// times 1/resolution) aligned at 0.5 (instant-ngp's distance_to_next_voxel). inv_d holds 1/d per axis; axes
// the ray is parallel to (d == 0) never exit; a point exactly on a boundary that the ray leaves through gives 0.
NPT_HD NPT_INLINE float march_distance_to_cell_exit(Vec3 p, Vec3 d, Vec3 inv_d, float cell) {
    const float inv_cell = 1.0f / cell;  // exact for power-of-two resolutions (the default 128)
    float t = INFINITY;
    for (int a = 0; a < 3; ++a) {
        if (d[a] == 0.0f) continue;
        // Cell boundaries are the integers of u: the cascade is centred at 0.5 and its cell count is even.
        const float u = (p[a] - 0.5f) * inv_cell;
        const float boundary = d[a] > 0.0f ? floorf(u) + 1.0f : floorf(u);
        t = fminf(t, (boundary - u) * cell * inv_d[a]);
    }
    return fmaxf(t, 0.0f);
}

// The same for p's cell in cascade c.
NPT_HD NPT_INLINE float march_distance_to_cell_exit(const OccupancyGridView& grid, Vec3 p, Vec3 d, int c) {
    const Vec3 inv_d(d.x != 0.0f ? 1.0f / d.x : 0.0f, d.y != 0.0f ? 1.0f / d.y : 0.0f,
                     d.z != 0.0f ? 1.0f / d.z : 0.0f);
    return march_distance_to_cell_exit(p, d, inv_d, grid.cascade_size(c) / float(grid.resolution));
}

// The first point of the step lattice (t, t + dt(t), ...) at or past t_target, at least one step on so that a
// zero distance still makes progress. Where the step is the same all the way to t_target (no cone angle, or
// both ends clamped) the lattice is jumped in one go; otherwise it is walked, with a cap that only float
// stagnation could reach.
NPT_HD NPT_INLINE float march_advance(const MarchParams& mp, float t, float t_target) {
    constexpr int k_max_walk = 4096;
    for (int i = 0; i < k_max_walk; ++i) {
        const float dt = march_step(mp, t);
        if (march_step(mp, t_target) == dt) return t + fmaxf(1.0f, ceilf((t_target - t) / dt)) * dt;
        t += dt;
        if (t >= t_target) return t;
    }
    return fmaxf(t, t_target);
}

// Where a march stands: a ray can be marched in pieces (the GPU renderer takes a few samples per ray per round)
// and gives the same samples as marching it in one go.
struct MarchCursor {
    float t = 0, t_far = 0;
    // With cone_angle 0 the steps are all equal and t is the lattice point t0 + k dt, computed directly rather
    // than by repeated addition, so that any thread can compute any lattice point exactly (the GPU trainer
    // splits a ray's lattice over several threads).
    float t0 = 0;
    uint32_t k = 0;
    int count = 0;      // samples emitted so far
    int skips = 0;      // empty cells skipped so far
    int max_skips = 0;  // see march_start
    bool stopped = false;
    NPT_HD NPT_INLINE bool done(const MarchParams& mp) const {
        return stopped || !(t < t_far) || count >= mp.max_samples;
    }
};

// Sets up the march of `ray` (unit direction, model space); false when there is nothing to march: non-finite
// input, non-positive steps, or a ray that misses. jitter in [0,1) offsets the first sample by jitter * step
// so that training sees every depth.
NPT_HD inline bool march_start(const MarchParams& mp, const OccupancyGridView& grid, const Ray& ray, float jitter,
                               MarchCursor* c) {
    if (mp.max_samples <= 0 || !isfinite(jitter) || !isfinite(mp.cone_angle)) return false;
    if (!(mp.min_step > 0.0f) || !(mp.max_step > 0.0f) || !isfinite(mp.min_step) || !isfinite(mp.max_step))
        return false;
    if (grid.cascades < 1 || grid.resolution < 1) return false;
    float t_near = 0.0f;
    float t_far = 0.0f;
    if (!march_bounds(mp, ray, &t_near, &t_far)) return false;
    c->t_far = fminf(t_far, mp.t_max);
    // Every pass either emits a sample or leaves a cell; a straight line leaves at most 3 (R + 1) cells of
    // each cascade, so this bound is never reached in exact arithmetic: it stops a ray whose t is so large
    // that steps no longer change it.
    c->max_skips = 3 * (grid.resolution + 2) * grid.cascades + 64;
    c->skips = 0;
    c->count = 0;
    c->stopped = false;
    c->t = t_near + jitter * march_step(mp, t_near);
    c->t0 = c->t;
    c->k = 0;
    return true;
}

// The lattice index of the first lattice point (t0 + k dt) at or past `target`, at least k + 1.
NPT_HD NPT_INLINE float march_lattice_next(float t0, float inv_dt, uint32_t k, float target) {
    const float kn = ceilf((target - t0) * inv_dt);
    return kn > float(k) + 1.0f ? kn : float(k) + 1.0f;
}

// Moves a uniform-step march (cone_angle 0) to the first lattice point inside [box_min, box_max] and ends it
// where the ray leaves the box. With the box around every occupied cell the samples do not change (no
// occupied cell lies outside it), only the empty space before and after is no longer walked. Returns false
// when the ray misses the box (nothing to march). Marches with a cone angle are left as they are.
NPT_HD inline bool march_clip(const MarchParams& mp, const Ray& ray, Vec3 box_min, Vec3 box_max, MarchCursor* c) {
    if (mp.cone_angle != 0.0f) return true;
    MarchParams box = mp;
    box.aabb_min = box_min;
    box.aabb_max = box_max;
    float t_in = 0.0f, t_out = 0.0f;
    if (!march_bounds(box, ray, &t_in, &t_out)) return false;
    const float dt = march_step(mp, c->t0);
    if (t_in > c->t) {
        // One lattice point early: a point a rounding before t_in may still lie in the box's first cell.
        const float kn = ceilf((t_in - c->t0) / dt) - 1.0f;
        if (!(kn < 4.0e9f)) return false;
        if (kn > float(c->k)) {
            c->k = uint32_t(kn);
            c->t = c->t0 + float(c->k) * dt;
        }
    }
    // One step of slack: a lattice point a rounding past t_out may still lie in the box's last cell.
    c->t_far = fminf(c->t_far, t_out + dt);
    return c->t < c->t_far;
}

// Where march_continue goes on from p = o + t d in an empty cell of cascade c: the exit of that cell, or of its
// whole coarse cell where that is empty too (no sample can lie in it), plus an epsilon (a millionth of a cell, or
// of t where t is larger) that moves the target off the boundary itself, so that rounding of o + t d cannot leave
// the next position in this cell.
NPT_HD NPT_INLINE float march_skip_target(const OccupancyGridView& grid, Vec3 p, float t, Vec3 d, Vec3 inv_d, int c) {
    const float cell = grid.cascade_size(c) / float(grid.resolution);
    const float eps = fmaxf(1e-6f * cell, 1e-6f * t);
    const float skip_cell = grid.coarse_occupied(p, c) ? cell : cell * float(OccupancyGridView::k_coarse);
    return t + march_distance_to_cell_exit(p, d, inv_d, skip_cell) + eps;
}

// Continues the march: calls visit(MarchSample) for each sample in order until visit returns false (the
// cursor then stands after that sample) or the march is done. Samples lie in occupied cells only; their dt is
// the step taken at them. A view without occupancy (has_occupancy() false) counts every cell as occupied.
template <typename Visit>
NPT_HD inline void march_continue(const MarchParams& mp, const OccupancyGridView& grid, const Ray& ray,
                                  MarchCursor& c, Visit&& visit) {
    const Vec3 inv_d(ray.d.x != 0.0f ? 1.0f / ray.d.x : 0.0f, ray.d.y != 0.0f ? 1.0f / ray.d.y : 0.0f,
                     ray.d.z != 0.0f ? 1.0f / ray.d.z : 0.0f);
    const bool lattice = mp.cone_angle == 0.0f;
    const float inv_dt = lattice ? 1.0f / march_step(mp, c.t0) : 0.0f;
    while (!c.stopped && c.t < c.t_far && c.count < mp.max_samples) {
        const float t = c.t;
        const Vec3 p = ray.at(t);
        const float dt = march_step(mp, t);
        const int cas = march_cascade(grid, p, dt);
        if (!grid.has_occupancy() || grid.is_occupied(p, cas)) {
            ++c.count;
            const bool more = visit(MarchSample{p, t, dt});
            float next = t + dt;
            if (lattice) next = c.t0 + float(++c.k) * dt;
            if (!(next > t)) {
                c.stopped = true;
                return;
            }
            c.t = next;
            if (!more) return;
        } else {
            if (++c.skips > c.max_skips) {
                c.stopped = true;
                return;
            }
            const float target = march_skip_target(grid, p, t, ray.d, inv_d, cas);
            float next;
            if (lattice) {
                const float kn = march_lattice_next(c.t0, inv_dt, c.k, target);
                if (!(kn < 4.0e9f)) {  // beyond any lattice a ray can have
                    c.stopped = true;
                    return;
                }
                c.k = uint32_t(kn);
                next = c.t0 + float(c.k) * dt;
            } else {
                next = march_advance(mp, t, target);
            }
            if (!(next > t)) {
                c.stopped = true;
                return;
            }
            c.t = next;
        }
    }
}

// Calls visit(MarchSample) for each sample of `ray` (unit direction, model space) in order, at most
// mp.max_samples of them, until visit returns false; returns how many were visited (march_start and
// march_continue in one go). Non-finite input, non-positive steps or a ray that misses give 0.
template <typename Visit>
NPT_HD inline int march_ray_visit(const MarchParams& mp, const OccupancyGridView& grid, const Ray& ray,
                                  float jitter, Visit&& visit) {
    MarchCursor c;
    if (!march_start(mp, grid, ray, jitter, &c)) return 0;
    march_continue(mp, grid, ray, c, visit);
    return c.count;
}

// Writes up to mp.max_samples samples of `ray` into out and returns how many (march_ray_visit).
NPT_HD inline int march_ray(const MarchParams& mp, const OccupancyGridView& grid, const Ray& ray, float jitter,
                            MarchSample* out) {
    int n = 0;
    return march_ray_visit(mp, grid, ray, jitter, [&](const MarchSample& s) {
        out[n++] = s;
        return true;
    });
}

}  // namespace npt::nerf
