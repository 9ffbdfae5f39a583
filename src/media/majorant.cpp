#include "media/majorant.h"

#include <algorithm>

#include "media/volume.h"

namespace npt::media {

std::vector<float> build_majorant(const VolumeGrid& g, int* nx, int* ny, int* nz) {
    const int b = k_majorant_block;
    // Cell c covers voxels b c - 1 .. b c + b (the trilinear support of its index range).
    auto cells = [](int n) { return (n + 1 + k_majorant_block - 1) / k_majorant_block; };
    *nx = cells(g.nx);
    *ny = cells(g.ny);
    *nz = cells(g.nz);
    std::vector<float> m(size_t(*nx) * size_t(*ny) * size_t(*nz), 0.0f);
    for (int k = 0; k < g.nz; ++k)
        for (int j = 0; j < g.ny; ++j)
            for (int i = 0; i < g.nx; ++i) {
                float d = g.density[(size_t(k) * size_t(g.ny) + size_t(j)) * size_t(g.nx) + size_t(i)];
                if (d <= 0.0f) continue;
                // Voxel i is in the support of cells whose range [b c - 1, b c + b] contains it.
                int ci0 = std::max(0, (i - b) / b), ci1 = std::min(*nx - 1, (i + 1) / b);
                int cj0 = std::max(0, (j - b) / b), cj1 = std::min(*ny - 1, (j + 1) / b);
                int ck0 = std::max(0, (k - b) / b), ck1 = std::min(*nz - 1, (k + 1) / b);
                for (int ck = ck0; ck <= ck1; ++ck)
                    for (int cj = cj0; cj <= cj1; ++cj)
                        for (int ci = ci0; ci <= ci1; ++ci) {
                            float& cell =
                                m[(size_t(ck) * size_t(*ny) + size_t(cj)) * size_t(*nx) + size_t(ci)];
                            cell = std::max(cell, d);
                        }
            }
    return m;
}

}  // namespace npt::media
