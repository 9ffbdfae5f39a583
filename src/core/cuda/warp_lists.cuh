// Building compact lists on the GPU with one atomic per warp instead of one per thread (every lane of the warp
// must make the call, with or without an item). Device code only.
#pragma once

#include <cstdint>

namespace npt::gpu {

// Appends `item` to `list` when `take`, in lane order within the warp.
__device__ __forceinline__ void warp_append(bool take, uint32_t item, uint32_t* list, uint32_t* count) {
    const unsigned mask = __ballot_sync(0xffffffffu, take);
    if (mask == 0) return;
    if (!take) return;  // the shuffle below is among the lanes in mask only
    const int lane = threadIdx.x & 31;
    const int leader = __ffs(mask) - 1;
    uint32_t base = 0;
    if (lane == leader) base = atomicAdd(count, uint32_t(__popc(mask)));
    base = __shfl_sync(mask, base, leader);
    list[base + __popc(mask & ((1u << lane) - 1u))] = item;
}

// Reserves `want` consecutive places and returns the first.
__device__ __forceinline__ uint32_t warp_reserve(uint32_t want, uint32_t* count) {
    const int lane = threadIdx.x & 31;
    uint32_t prefix = want;  // inclusive scan of `want` over the warp
#pragma unroll
    for (int off = 1; off < 32; off <<= 1) {
        const uint32_t o = __shfl_up_sync(0xffffffffu, prefix, off);
        if (lane >= off) prefix += o;
    }
    const uint32_t total = __shfl_sync(0xffffffffu, prefix, 31);
    uint32_t base = 0;
    if (lane == 31 && total > 0) base = atomicAdd(count, total);
    base = __shfl_sync(0xffffffffu, base, 31);
    return base + prefix - want;
}

}  // namespace npt::gpu
