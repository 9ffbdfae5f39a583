#include "nerf/ngp_hash_grid.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "core/error.h"

namespace npt::nerf {

TcnnLevel tcnn_level(const HashGridConfig& cfg, float per_level_scale, int level) {
    TcnnLevel lv;
    lv.scale = exp2f(float(level) * log2f(per_level_scale)) * float(cfg.base_resolution) - 1.0f;
    lv.resolution = uint32_t(ceilf(lv.scale)) + 1u;
    const uint64_t r = lv.resolution, cube = r * r * r;
    const uint64_t table = cfg.table_size();
    // Rounded up to 8 entries for aligned loads, capped at the hash table size (GridEncoding's constructor).
    lv.size = uint32_t(std::min((cube + 7) / 8 * 8, table));
    // grid_index hashes when the table is smaller than the dense stride; the stride saturates past 1625 per
    // axis (1625^3 is the largest cube below 2^32).
    const uint64_t stride = r <= 1625u ? cube : 0xFFFFFFFFull;
    lv.dense = !(uint64_t(lv.size) < stride);
    return lv;
}

uint32_t tcnn_entry(const TcnnLevel& lv, uint32_t x, uint32_t y, uint32_t z) {
    if (lv.dense) return (x + y * lv.resolution + z * lv.resolution * lv.resolution) % lv.size;
    return ((x * 1u) ^ (y * 2654435761u) ^ (z * 805459861u)) % lv.size;
}

namespace {

// Summed-area table of the innermost cascade's occupied flags, so that "is any cell near this vertex
// occupied" costs eight lookups.
class OccupiedSums {
  public:
    explicit OccupiedSums(const OccupancyGrid& g) : m_r(g.resolution()) {
        const OccupancyGridView v = g.view();
        const size_t n = size_t(m_r) + 1;
        m_sum.assign(n * n * n, 0u);
        for (int z = 0; z < m_r; ++z)
            for (int y = 0; y < m_r; ++y)
                for (int x = 0; x < m_r; ++x) {
                    const uint32_t occ =
                        v.occupied[size_t(x) + size_t(y) * m_r + size_t(z) * m_r * m_r] ? 1u : 0u;
                    at(x + 1, y + 1, z + 1) = occ + at(x, y + 1, z + 1) + at(x + 1, y, z + 1) +
                                              at(x + 1, y + 1, z) - at(x, y, z + 1) - at(x, y + 1, z) -
                                              at(x + 1, y, z) + at(x, y, z);
                }
    }
    // Any occupied cell overlapping the box [lo, hi] (unit-cube coordinates)?
    bool any(const float lo[3], const float hi[3]) const {
        int a[3], b[3];
        for (int k = 0; k < 3; ++k) {
            const float l = std::max(lo[k], 0.0f), h = std::min(hi[k], 1.0f);
            if (!(l <= h)) return false;
            a[k] = std::clamp(int(std::floor(l * float(m_r))), 0, m_r - 1);
            b[k] = std::clamp(int(std::floor(h * float(m_r))), 0, m_r - 1) + 1;
        }
        const int64_t s = int64_t(at(b[0], b[1], b[2])) - at(a[0], b[1], b[2]) - at(b[0], a[1], b[2]) -
                          at(b[0], b[1], a[2]) + at(a[0], a[1], b[2]) + at(a[0], b[1], a[2]) +
                          at(b[0], a[1], a[2]) - at(a[0], a[1], a[2]);
        return s > 0;
    }

  private:
    uint32_t at(int x, int y, int z) const {
        const size_t n = size_t(m_r) + 1;
        return m_sum[size_t(x) + size_t(y) * n + size_t(z) * n * n];
    }
    uint32_t& at(int x, int y, int z) {
        const size_t n = size_t(m_r) + 1;
        return m_sum[size_t(x) + size_t(y) * n + size_t(z) * n * n];
    }
    int m_r;
    std::vector<uint32_t> m_sum;
};

// Weight of a vertex in the fit of an inexact level: the snapshot's values matter where something is seen.
constexpr float k_empty_weight = 1e-4f;

void fit_level(const HashGridConfig& cfg, const HashLevel& ours, const TcnnLevel& theirs, const float* src,
               const OccupiedSums& occupied, float* dst, NgpLevelReport& report) {
    const int nf = cfg.features_per_level;
    const uint32_t v = ours.vertices;
    const uint32_t table = cfg.table_size();
    std::vector<float> weight_sum(table, 0.0f);
    std::vector<uint8_t> near_occupied(size_t(v) * v * v);
    const float support = 1.0f / ours.scale;  // a vertex's trilinear hat reaches one cell either way
    for (uint32_t z = 0; z < v; ++z)
        for (uint32_t y = 0; y < v; ++y)
            for (uint32_t x = 0; x < v; ++x) {
                const uint32_t g[3] = {x, y, z};
                float lo[3], hi[3];
                for (int k = 0; k < 3; ++k) {
                    const float q = (float(g[k]) - 0.5f) / ours.scale;
                    lo[k] = q - support;
                    hi[k] = q + support;
                }
                const bool occ = occupied.any(lo, hi);
                near_occupied[x + size_t(y) * v + size_t(z) * v * v] = occ;
                const float w = occ ? 1.0f : k_empty_weight;
                const uint32_t e = hash_grid_index(cfg, ours, x, y, z);
                const uint32_t s = tcnn_entry(theirs, x, y, z);
                weight_sum[e] += w;
                for (int f = 0; f < nf; ++f) dst[size_t(e) * nf + f] += w * src[size_t(s) * nf + f];
            }
    for (uint32_t e = 0; e < table; ++e)
        if (weight_sum[e] > 0.0f)
            for (int f = 0; f < nf; ++f) dst[size_t(e) * nf + f] /= weight_sum[e];
    for (uint32_t z = 0; z < v; ++z)
        for (uint32_t y = 0; y < v; ++y)
            for (uint32_t x = 0; x < v; ++x) {
                if (!near_occupied[x + size_t(y) * v + size_t(z) * v * v]) continue;
                ++report.vertices_checked;
                const uint32_t e = hash_grid_index(cfg, ours, x, y, z);
                const uint32_t s = tcnn_entry(theirs, x, y, z);
                float err = 0.0f;
                for (int f = 0; f < nf; ++f) {
                    const float want = src[size_t(s) * nf + f];
                    const float d = std::fabs(dst[size_t(e) * nf + f] - want);
                    // A mean of equal values may round by an ulp or so; that is not a loss.
                    if (d > 1e-6f * std::max(1.0f, std::fabs(want))) err = std::max(err, d);
                }
                if (err > 0.0f) ++report.vertices_off;
                report.max_error = std::max(report.max_error, err);
            }
}

}  // namespace

std::vector<NgpLevelReport> convert_hash_grid(const HashGridConfig& cfg, float per_level_scale,
                                              const float* src, const OccupancyGrid& occupancy, float* dst) {
    const int nf = cfg.features_per_level;
    std::fill(dst, dst + cfg.param_count(), 0.0f);
    std::vector<NgpLevelReport> reports;
    const OccupiedSums occupied(occupancy);
    size_t src_entries = 0;
    for (int l = 0; l < cfg.levels; ++l) {
        const TcnnLevel theirs = tcnn_level(cfg, per_level_scale, l);
        const HashLevel ours = hash_level(cfg, l);
        if (theirs.scale != ours.scale)
            throw Error("hash-grid level " + std::to_string(l) + ": scale " + std::to_string(ours.scale) +
                        " differs from the snapshot's " + std::to_string(theirs.scale));
        const float* s = src + src_entries * nf;
        float* d = dst + size_t(l) * cfg.table_size() * nf;
        NgpLevelReport r;
        r.level = l;
        r.dense_in_snapshot = theirs.dense;
        r.dense_here = ours.dense;
        if (ours.dense) {
            // Every vertex has its own entry: copy the value tiny-cuda-nn reads there (aliasing included).
            const uint32_t v = ours.vertices;
            for (uint32_t z = 0; z < v; ++z)
                for (uint32_t y = 0; y < v; ++y)
                    for (uint32_t x = 0; x < v; ++x) {
                        const uint32_t e = hash_grid_index(cfg, ours, x, y, z);
                        const uint32_t t = tcnn_entry(theirs, x, y, z);
                        std::memcpy(d + size_t(e) * nf, s + size_t(t) * nf, sizeof(float) * size_t(nf));
                    }
        } else if (!theirs.dense) {
            // Same hash, same table size, same vertex coordinates: the table carries over as it is.
            std::memcpy(d, s, sizeof(float) * size_t(theirs.size) * size_t(nf));
        } else {
            r.exact = false;
            fit_level(cfg, ours, theirs, s, occupied, d, r);
        }
        reports.push_back(r);
        src_entries += theirs.size;
    }
    return reports;
}

}  // namespace npt::nerf
