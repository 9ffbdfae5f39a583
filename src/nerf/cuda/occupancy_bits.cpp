#include "nerf/cuda/occupancy_bits.h"

#include <algorithm>

#include "nerf/cuda/occupancy_kernels.h"

namespace npt::nerf::cuda {

OccupancyBits occupancy_bits(const OccupancyGridView& g) {
    OccupancyBits out;
    const int res = g.resolution;
    const size_t per_cascade = size_t(res) * res * res, cells = per_cascade * size_t(g.cascades);
    out.occupied.assign((cells + 31) / 32, 0u);
    const bool coarse = coarse_cells_fit(res);
    const int k = OccupancyGridView::k_coarse, rc = res / k;
    if (coarse) out.coarse.assign(coarse_words(g.cascades, res), 0u);
    for (size_t i = 0; i < cells; ++i) {
        if (!g.occupied[i]) continue;
        out.occupied[i >> 5] |= 1u << (i & 31);
        const size_t c = i / per_cascade, local = i % per_cascade;
        const size_t xyz[3] = {local % res, (local / res) % res, local / (size_t(res) * res)};
        const float size = float(1 << c), base = 0.5f - 0.5f * size, w = size / float(res);
        for (int a = 0; a < 3; ++a) {
            out.box_min[a] = std::min(out.box_min[a], base + float(xyz[a]) * w);
            out.box_max[a] = std::max(out.box_max[a], base + float(xyz[a] + 1) * w);
        }
        if (coarse) {
            const size_t ci = c * size_t(rc) * rc * rc + xyz[0] / k + (xyz[1] / k) * rc + (xyz[2] / k) * size_t(rc) * rc;
            out.coarse[ci >> 5] |= 1u << (ci & 31);
        }
    }
    return out;
}

}  // namespace npt::nerf::cuda
