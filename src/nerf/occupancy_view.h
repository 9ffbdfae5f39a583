// Read side of the occupancy grid (instant-ngp's density grid), NPT_HD so that training, rendering and the
// GPU share it. Model space is the unit cube [0,1]^3 centred at 0.5 (instant-ngp's coordinates); cascade c
// covers the cube of side 2^c centred at 0.5 with `resolution` cells per axis, so each cascade halves the
// resolution of the one inside it. Cells are stored cascade after cascade, x fastest: index =
// c * R^3 + x + y * R + z * R^2.
#pragma once

#include <math.h>

#include <cstdint>

#include "core/platform.h"
#include "core/vec.h"

namespace npt::nerf {

struct OccupancyGridView {
    const uint8_t* occupied = nullptr;  // one byte per cell, 0 or 1
    int cascades = 1;
    int resolution = 128;
    // Instead of `occupied` (the GPU's form): one bit per cell, cell i at bit i % 32 of word i / 32. 8x smaller,
    // so that a march's dependent lookups stay in the L1 cache.
    const uint32_t* occupied_bits = nullptr;
    // Optional (the GPU's marches): one bit per coarse cell of k_coarse^3 cells, set when any of them is
    // occupied, laid out like the cells (cascade after cascade, x fastest, resolution / k_coarse per axis). A
    // march crosses an empty coarse cell in one skip instead of k_coarse; the samples are the same. Needs
    // resolution % (2 k_coarse) == 0.
    const uint32_t* coarse_bits = nullptr;
    static constexpr int k_coarse = 8;

    // False: every cell counts as occupied.
    NPT_HD NPT_INLINE bool has_occupancy() const { return occupied != nullptr || occupied_bits != nullptr; }

    // The smallest cascade that contains p (clamped to the last one).
    NPT_HD NPT_INLINE int cascade_of(Vec3 p) const {
        if (cascades == 1) return 0;  // the common aabb_scale 1: no frexpf per sample
        const float m = fmaxf(fabsf(p.x - 0.5f), fmaxf(fabsf(p.y - 0.5f), fabsf(p.z - 0.5f)));
        if (!(m > 0.0f)) return 0;  // frexpf(0) gives exponent 0, which would say cascade 1 at the centre
        int exponent = 0;
        frexpf(m, &exponent);  // m in [2^(e-1), 2^e)
        const int c = exponent + 1;
        return c < 0 ? 0 : (c > cascades - 1 ? cascades - 1 : c);
    }
    NPT_HD NPT_INLINE float cascade_size(int c) const { return float(1 << c); }
    // Cell index of p in cascade c on a grid of `res` cells per axis, or -1 when p lies outside that cascade.
    NPT_HD NPT_INLINE int64_t cell_index_at(Vec3 p, int c, int res) const {
        const float size = cascade_size(c);
        const float lo = 0.5f - 0.5f * size;
        int idx[3];
        // Cells per unit, one multiplication: equal to (p - lo) / size * res for power-of-two sizes and
        // resolutions (every factor exact), the cheap form of the same cell on CPU and GPU alike.
        const float cells_per_unit = float(res) / size;
        for (int a = 0; a < 3; ++a) {
            const float u = (p[a] - lo) * cells_per_unit;
            if (!(u >= 0.0f) || u >= float(res)) return -1;
            idx[a] = int(u);
        }
        // 32-bit arithmetic (a grid has at most 2^28 cells, OccupancyGrid's limit): 64-bit products and
        // conversions cost several instructions each on a GPU.
        const uint32_t r = uint32_t(res);
        return int64_t(uint32_t(c) * r * r * r + uint32_t(idx[0]) + uint32_t(idx[1]) * r + uint32_t(idx[2]) * r * r);
    }
    NPT_HD NPT_INLINE int64_t cell_index(Vec3 p, int c) const { return cell_index_at(p, c, resolution); }
    NPT_HD NPT_INLINE bool is_occupied(Vec3 p, int c) const {
        const int64_t i = cell_index(p, c);
        if (i < 0) return false;
        if (occupied_bits) return (occupied_bits[i >> 5] >> (i & 31)) & 1u;
        return occupied[i] != 0;
    }
    // False only where coarse_bits says the whole coarse cell around p is empty.
    NPT_HD NPT_INLINE bool coarse_occupied(Vec3 p, int c) const {
        if (coarse_bits == nullptr) return true;
        const int64_t i = cell_index_at(p, c, resolution / k_coarse);
        return i < 0 || ((coarse_bits[i >> 5] >> (i & 31)) & 1u);
    }
};

}  // namespace npt::nerf
