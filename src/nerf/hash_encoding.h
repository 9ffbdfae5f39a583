// Multiresolution hash encoding of a point in [0,1]^3 (Müller et al. 2022, instant-ngp), forward and
// backward. One (index, weight) function per level is shared by both passes, so that a CUDA kernel doing
// atomic or per-thread accumulation of the parameter gradient sees exactly the same corners as the forward
// pass.
//
// Convention (instant-ngp / tiny-cuda-nn, with one more vertex per axis, see below):
//   scale_l    = exp2(l * log2(per_level_scale)) * base_resolution - 1
//   position   = p * scale_l + 0.5          (p clamped to [0,1]^3; vertex i sits at p = (i - 0.5) / scale_l)
//   vertices   = ceil(scale_l) + 2 per axis  (tiny-cuda-nn uses ceil + 1 and lets the largest corner alias
//                                             into the next row at p close to 1; +2 keeps every corner real)
//   dense      iff vertices^3 <= T = 2^log2_table_size: index = x + y*V + z*V*V
//   hashed     otherwise: index = (x * 1) ^ (y * 2654435761) ^ (z * 805459861) in uint32 arithmetic, mod T
// Parameters: levels x T x F floats, level-major, the F features of one entry contiguous (dense levels use
// the first V^3 entries of their T). Corner indices are global entry indices (level * T + local): the
// features of a corner are params[index * F + f].
#pragma once

#include <math.h>

#include "core/platform.h"
#include "core/vec.h"

namespace npt::nerf {

struct HashGridConfig {
    int levels = 16;
    int features_per_level = 2;
    int log2_table_size = 19;
    int base_resolution = 16;
    float per_level_scale = 1.5f;  // instant-ngp's configs/nerf/base.json
    NPT_HD NPT_INLINE uint32_t table_size() const { return uint32_t(1) << log2_table_size; }
    NPT_HD NPT_INLINE size_t param_count() const {
        return size_t(levels) * table_size() * size_t(features_per_level);
    }
    NPT_HD NPT_INLINE int output_dims() const { return levels * features_per_level; }
};

// The growth factor that makes the finest level reach `finest_resolution` (the paper's b, eq. 3).
inline float per_level_scale_for(int base_resolution, float finest_resolution, int levels) {
    if (levels <= 1) return 1.0f;
    return expf(logf(finest_resolution / float(base_resolution)) / float(levels - 1));
}

// What one level looks like; computed from the config on the fly so that the config stays a plain struct.
struct HashLevel {
    float scale = 0;        // grid position = p * scale + 0.5
    uint32_t vertices = 0;  // per axis
    bool dense = false;     // vertices^3 <= T
};

NPT_HD NPT_INLINE HashLevel hash_level(const HashGridConfig& cfg, int level) {
    HashLevel lv;
    lv.scale = exp2f(float(level) * log2f(cfg.per_level_scale)) * float(cfg.base_resolution) - 1.0f;
    lv.vertices = uint32_t(ceilf(lv.scale)) + 2u;
    // 64-bit: fine levels have thousands of vertices per axis, whose cube overflows 32 bits.
    const uint64_t v = lv.vertices;
    lv.dense = v * v * v <= uint64_t(cfg.table_size());
    return lv;
}

struct HashCorner {
    uint32_t index = 0;  // global entry index: features at params[index * F + f]
    float weight = 0;    // trilinear weight; the 8 weights of a level sum to 1
};

NPT_HD NPT_INLINE uint32_t hash_grid_index(const HashGridConfig& cfg, const HashLevel& lv, uint32_t x,
                                           uint32_t y, uint32_t z) {
    const uint32_t mask = cfg.table_size() - 1u;
    if (lv.dense) return x + y * lv.vertices + z * lv.vertices * lv.vertices;
    return ((x * 1u) ^ (y * 2654435761u) ^ (z * 805459861u)) & mask;
}

constexpr int k_max_hash_levels = 32;

// Every level's HashLevel, computed once per batch instead of once per sample (exp2f/log2f per level add up).
struct HashLevels {
    HashLevel level[k_max_hash_levels];
};
NPT_HD NPT_INLINE HashLevels hash_levels(const HashGridConfig& cfg) {
    HashLevels h;
    for (int l = 0; l < cfg.levels && l < k_max_hash_levels; ++l) h.level[l] = hash_level(cfg, l);
    return h;
}

// The 8 corners of p's cell at `level` (whose HashLevel is lv), in the order bit 0 = x, bit 1 = y, bit 2 = z
// of the corner offset.
NPT_HD NPT_INLINE void hash_level_corners(const HashGridConfig& cfg, const HashLevel& lv, int level, Vec3 p,
                                          HashCorner out[8]) {
    uint32_t base[3];
    float frac[3];
    for (int a = 0; a < 3; ++a) {
        // Clamping keeps every corner inside the level for any input; the position gradient is not needed.
        // Comparisons rather than fminf/fmaxf, which are library calls without -ffinite-math-only; NaN -> 0.
        const float pa = !(p[a] > 0.0f) ? 0.0f : (p[a] < 1.0f ? p[a] : 1.0f);
        const float pos = pa * lv.scale + 0.5f;
        const float fl = floorf(pos);
        base[a] = uint32_t(fl);
        frac[a] = pos - fl;
    }
    const uint32_t level_offset = uint32_t(level) * cfg.table_size();
    for (int c = 0; c < 8; ++c) {
        float w = 1.0f;
        uint32_t g[3];
        for (int a = 0; a < 3; ++a) {
            const bool hi = (c >> a) & 1;
            g[a] = base[a] + (hi ? 1u : 0u);
            w *= hi ? frac[a] : 1.0f - frac[a];
        }
        out[c].index = level_offset + hash_grid_index(cfg, lv, g[0], g[1], g[2]);
        out[c].weight = w;
    }
}

NPT_HD NPT_INLINE void hash_level_corners(const HashGridConfig& cfg, int level, Vec3 p, HashCorner out[8]) {
    hash_level_corners(cfg, hash_level(cfg, level), level, p, out);
}

// out[l * F + f] = sum over the 8 corners of level l of weight * params[index * F + f], with the levels
// precomputed (hash_levels) as batched and per-sample callers do.
NPT_HD NPT_INLINE void hash_encode(const HashGridConfig& cfg, const HashLevels& levels, const float* params,
                                   Vec3 p, float* out) {
    const int nf = cfg.features_per_level;
    for (int l = 0; l < cfg.levels; ++l) {
        HashCorner corners[8];
        hash_level_corners(cfg, levels.level[l], l, p, corners);
        for (int f = 0; f < nf; ++f) {
            float acc = 0.0f;
            for (int c = 0; c < 8; ++c) acc += corners[c].weight * params[size_t(corners[c].index) * nf + f];
            out[l * nf + f] = acc;
        }
    }
}

// The same, computing the levels on the way (tests, one-off lookups).
NPT_HD NPT_INLINE void hash_encode(const HashGridConfig& cfg, const float* params, Vec3 p, float* out) {
    hash_encode(cfg, hash_levels(cfg), params, p, out);
}

// Level l's part of hash_encode_backward: d_params[index * F + f] += weight * d_out[l * F + f] over its 8
// corners. A level's entries are its own, so callers may run the levels in parallel.
NPT_HD NPT_INLINE void hash_level_backward(const HashGridConfig& cfg, const HashLevel& lv, int level, Vec3 p,
                                           const float* d_out, float* d_params) {
    const int nf = cfg.features_per_level;
    HashCorner corners[8];
    hash_level_corners(cfg, lv, level, p, corners);
    for (int c = 0; c < 8; ++c)
        for (int f = 0; f < nf; ++f)
            d_params[size_t(corners[c].index) * nf + f] += corners[c].weight * d_out[level * nf + f];
}

// d_params[index * F + f] += weight * d_out[l * F + f]: the encoding is linear in the parameters, so this is
// the exact transpose of hash_encode. Serial accumulation; a parallel caller runs hash_level_backward per
// level, or uses hash_level_corners with atomics.
NPT_HD NPT_INLINE void hash_encode_backward(const HashGridConfig& cfg, Vec3 p, const float* d_out,
                                            float* d_params) {
    for (int l = 0; l < cfg.levels; ++l) hash_level_backward(cfg, hash_level(cfg, l), l, p, d_out, d_params);
}

}  // namespace npt::nerf
