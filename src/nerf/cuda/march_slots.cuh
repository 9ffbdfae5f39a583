// One round of a batched march (the view renderer's and the path tracer's NeRF pass): a live ray or segment takes
// up to k more samples from its cursor into its own scratch slots, then the warp reserves their places in the
// round's packed sample list (RenderSlots) with one atomic. Device code only.
#pragma once

#include "core/cuda/warp_lists.cuh"
#include "nerf/cuda/render_kernels.h"
#include "nerf/object_cut.h"
#include "nerf/ray_march.h"

namespace npt::nerf::cuda {

// Item a of the round's live list marches `ray` from cursor c and packs its samples under `owner` (the index of its
// direction for the MLP). Every lane of the warp must call it; `live` is false for lanes without an item. Samples
// outside an active `cut` are passed over, as the CPU view renderer drops them (they still count toward
// mp.max_samples, as there); the path tracer's callers leave it inactive, which the inlining folds away.
__device__ __forceinline__ void march_into_slots(bool live, uint32_t a, uint32_t owner, const MarchParams& mp,
                                                 const OccupancyGridView& grid, const Ray& ray, MarchCursor& c,
                                                 int k, const RenderSlots& slots, const ObjectCut& cut = {}) {
    int used = 0;
    float4* mine = slots.scratch + size_t(a) * size_t(k);
    if (live)
        march_continue(mp, grid, ray, c, [&](const MarchSample& s) {
            if (cut.outside(s.position)) return true;
            mine[used++] = make_float4(s.position.x, s.position.y, s.position.z, s.dt);
            return used < k;
        });
    const uint32_t base = gpu::warp_reserve(uint32_t(used), slots.count);
    if (!live) return;
    for (int q = 0; q < used; ++q) {
        const float4 v = mine[q];
        slots.pos[base + q] = Vec3(v.x, v.y, v.z);
        slots.dt[base + q] = v.w;
        slots.pixel[base + q] = owner;
    }
    slots.first[a] = base;
    slots.used[a] = uint8_t(used);
}

}  // namespace npt::nerf::cuda

namespace npt::nerf::cuda {

// The same round for one ray per warp, for rays whose one-thread march would be a long dependent chain (the few
// long segments left in a round's tail). Only for uniform steps (cone_angle 0): the lattice t0 + k dt is then
// global, so lane l tests lattice point c.k + l and the warp finds 32 points' occupancy at once. The samples are
// march_continue's: the lattice points in occupied cells, in order, at most k this round and mp.max_samples in
// all, less the points march_continue's skip steps over (an occupied point within the skip's epsilon past the
// exit of the empty cell before it: a point whose predecessor is empty is taken only where the skip from that
// predecessor reaches it). Where a chunk of 32 ends in an empty cell the march jumps on from its last point by
// the same skip. Every lane calls it with the same arguments and cursor and leaves with the same cursor; lane 0
// writes slots.first/used[a].
__device__ __forceinline__ void warp_march_into_slots(uint32_t a, uint32_t owner, const MarchParams& mp,
                                                      const OccupancyGridView& grid, const Ray& ray, MarchCursor& c,
                                                      int k, const RenderSlots& slots) {
    constexpr unsigned all = 0xffffffffu;
    const int lane = int(threadIdx.x & 31);
    const unsigned below = (1u << lane) - 1u;
    float4* mine = slots.scratch + size_t(a) * size_t(k);
    const float dt = march_step(mp, c.t0);
    const float inv_dt = 1.0f / dt;
    const Vec3 inv_d(ray.d.x != 0.0f ? 1.0f / ray.d.x : 0.0f, ray.d.y != 0.0f ? 1.0f / ray.d.y : 0.0f,
                     ray.d.z != 0.0f ? 1.0f / ray.d.z : 0.0f);
    int used = 0;
    while (used < k && !c.done(mp)) {
        const uint32_t kl = c.k + uint32_t(lane);
        const float t = c.t0 + float(kl) * dt;
        const float t_before = __shfl_up_sync(all, t, 1);
        // A lattice that no longer advances in float (t huge against dt) stops the march, as in march_continue.
        const bool advancing = lane == 0 || t > t_before;
        const bool valid = t < c.t_far && advancing && kl >= c.k;
        const Vec3 p = ray.at(t);
        const int cas = valid ? march_cascade(grid, p, dt) : 0;
        const bool in_cell = valid && (!grid.has_occupancy() || grid.is_occupied(p, cas));
        // Lane 0's predecessor was occupied, or skipped from already, or there is none (the march's start). (The
        // shuffle outside the condition: every lane of `all` must take part in it.)
        const bool before_in_cell = __shfl_up_sync(all, in_cell, 1);
        const bool after_empty = lane > 0 && !before_in_cell;
        bool occupied = in_cell;
        if (in_cell && after_empty) {
            const float tp = c.t0 + float(kl - 1u) * dt;
            const Vec3 pp = ray.at(tp);
            const float target = march_skip_target(grid, pp, tp, ray.d, inv_d, march_cascade(grid, pp, dt));
            occupied = march_lattice_next(c.t0, inv_dt, kl - 1u, target) <= float(kl);
        }
        const unsigned invalid = __ballot_sync(all, !valid);
        const int first_invalid = invalid ? __ffs(invalid) - 1 : 32;
        const unsigned in_range = first_invalid == 32 ? all : (1u << first_invalid) - 1u;
        const unsigned hits = __ballot_sync(all, occupied) & in_range;
        const int found = __popc(hits);
        const int room = min(k - used, mp.max_samples - c.count);
        const int rank = __popc(hits & below);
        if (occupied && (hits >> lane & 1u) && rank < room) mine[used + rank] = make_float4(p.x, p.y, p.z, dt);
        if (found >= room) {
            // The quota ends inside this chunk: the cursor stands after the room-th hit.
            const unsigned last = __ballot_sync(all, (hits >> lane & 1u) && rank == room - 1);
            used += room;
            c.count += room;
            c.k += uint32_t(__ffs(last));  // that lane + 1
            c.t = c.t0 + float(c.k) * dt;
            break;
        }
        used += found;
        c.count += found;
        if (invalid) {
            // Past the end of the segment, or a lattice that stopped advancing.
            c.k += uint32_t(first_invalid);
            c.t = __shfl_sync(all, t, first_invalid);
            if (c.t < c.t_far) c.stopped = true;
            break;
        }
        // All 32 points tested: go on after them, or, where the last one is empty, from the far side of its
        // empty cell (march_continue's skip).
        float kn = float(c.k) + 32.0f;
        if (lane == 31 && !in_cell)
            kn = fmaxf(kn, march_lattice_next(c.t0, inv_dt, kl, march_skip_target(grid, p, t, ray.d, inv_d, cas)));
        kn = __shfl_sync(all, kn, 31);
        if (!(kn < 4.0e9f)) {  // beyond any lattice a ray can have
            c.stopped = true;
            break;
        }
        c.k = uint32_t(kn);
        c.t = c.t0 + float(c.k) * dt;
    }
    __syncwarp();  // the lanes wrote `mine`; they copy it below in another order
    uint32_t base = 0;
    if (lane == 0 && used > 0) base = atomicAdd(slots.count, uint32_t(used));
    base = __shfl_sync(all, base, 0);
    for (int q = lane; q < used; q += 32) {
        const float4 v = mine[q];
        slots.pos[base + q] = Vec3(v.x, v.y, v.z);
        slots.dt[base + q] = v.w;
        slots.pixel[base + q] = owner;
    }
    if (lane == 0) {
        slots.first[a] = base;
        slots.used[a] = uint8_t(used);
    }
}

}  // namespace npt::nerf::cuda
