// instant-ngp's raw RGBA-σ grid (grid_writers.h, docs/formats.md): dense, one z-slab at a time.
#include <bit>
#include <fstream>
#include <vector>

#include "bake/grid_writers.h"
#include "core/error.h"
#include "core/temp_file.h"

namespace npt::bake {

static_assert(std::endian::native == std::endian::little, "raw grids are little-endian float32");

void write_raw(const std::filesystem::path& path, const BakedGrid& grid) {
    const BakeLayout& L = grid.layout;
    check_raw_size(L);
    const size_t w = size_t(L.dims[0]), h = size_t(L.dims[1]);
    TempFile tmp(path);
    std::ofstream out(tmp.path(), std::ios::binary | std::ios::trunc);
    if (!out) throw Error(path.string() + ": cannot write (cannot create a file in its folder)");
    std::vector<float> slab(w * h * 4);
    size_t v = 0;  // voxels are ordered by k: one pass over them
    for (int k = 0; k < L.dims[2]; ++k) {
        std::fill(slab.begin(), slab.end(), 0.0f);
        for (; v < grid.size() && grid.coords[3 * v + 2] == k; ++v) {
            const size_t i = size_t(grid.coords[3 * v]), j = size_t(grid.coords[3 * v + 1]);
            float* px = &slab[((h - 1 - j) * w + i) * 4];  // the file's first row is the top one
            px[0] = grid.color[v].x;
            px[1] = grid.color[v].y;
            px[2] = grid.color[v].z;
            px[3] = grid.sigma[v];
        }
        out.write(reinterpret_cast<const char*>(slab.data()), std::streamsize(slab.size() * sizeof(float)));
        if (!out) throw Error(path.string() + ": write failed (disk full?)");
    }
    out.close();
    if (!out) throw Error(path.string() + ": write failed (disk full?)");
    tmp.commit();
}

}  // namespace npt::bake
