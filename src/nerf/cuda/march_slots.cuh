// One round of a batched march (the view renderer's and the path tracer's NeRF pass): a live ray or segment takes
// up to k more samples from its cursor into its own scratch slots, then the warp reserves their places in the
// round's packed sample list (RenderSlots) with one atomic. Device code only.
#pragma once

#include "core/cuda/warp_lists.cuh"
#include "nerf/cuda/render_kernels.h"
#include "nerf/ray_march.h"

namespace npt::nerf::cuda {

// Item a of the round's live list marches `ray` from cursor c and packs its samples under `owner` (the index of its
// direction for the MLP). Every lane of the warp must call it; `live` is false for lanes without an item.
__device__ __forceinline__ void march_into_slots(bool live, uint32_t a, uint32_t owner, const MarchParams& mp,
                                                 const OccupancyGridView& grid, const Ray& ray, MarchCursor& c,
                                                 int k, const RenderSlots& slots) {
    int used = 0;
    float4* mine = slots.scratch + size_t(a) * size_t(k);
    if (live)
        march_continue(mp, grid, ray, c, [&](const MarchSample& s) {
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
