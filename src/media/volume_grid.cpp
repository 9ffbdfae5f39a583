#include "media/volume_grid.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/memory.h"
#include "media/nanovdb_reader.h"
#include "media/openvdb_reader.h"
#include "media/raw_grid_reader.h"

namespace npt::media {
namespace {

// The per-sample code assumes finite, non-negative densities and finite colours (grid.h): enforce it here,
// once for every format, with one warning per file rather than one per voxel.
void sanitize(VolumeGrid& g) {
    size_t bad_density = 0, bad_color = 0;
    for (float& v : g.density) {
        if (!(std::isfinite(v) && v >= 0.0f)) {  // NaN fails both tests
            v = 0.0f;
            ++bad_density;
        }
    }
    for (Vec3& c : g.color) {
        bool bad = false;
        for (float* f : {&c.x, &c.y, &c.z}) {
            if (!std::isfinite(*f)) {
                *f = 0.0f;
                bad = true;
            }
        }
        bad_color += bad;
    }
    if (bad_density || bad_color)
        spdlog::warn("{}: {} NaN, infinite or negative densities and {} non-finite colours set to 0",
                     g.source, bad_density, bad_color);
}

// A raw grid's voxels are samples at the cell centres of the whole cube. Inside the cube the field is
// reconstructed clamp-to-edge, not faded to zero over the last half voxel: a one-voxel border repeats the
// outermost samples (index space shifts by one), and the cube's faces cut the field exactly, so a constant
// grid renders as a constant medium.
void pad_clamp_to_edge(VolumeGrid& g) {
    const size_t w = size_t(g.nx), h = size_t(g.ny), d = size_t(g.nz);
    const size_t px = w + 2, py = h + 2, pz = d + 2;
    std::vector<float> density(px * py * pz);
    std::vector<Vec3> color(density.size());
    auto inner = [](size_t p, size_t n) { return p == 0 ? 0 : (p > n ? n - 1 : p - 1); };
    for (size_t k = 0; k < pz; ++k)
        for (size_t j = 0; j < py; ++j)
            for (size_t i = 0; i < px; ++i) {
                const size_t src = (inner(k, d) * h + inner(j, h)) * w + inner(i, w);
                const size_t dst = (k * py + j) * px + i;
                density[dst] = g.density[src];
                color[dst] = g.color[src];
            }
    g.density = std::move(density);
    g.color = std::move(color);
    g.nx = int(px);
    g.ny = int(py);
    g.nz = int(pz);
    g.local_to_index.t += Vec3(1.0f);
}

}  // namespace

void check_dense_size(const std::string& where, const std::string& what, double nx, double ny, double nz,
                      size_t max_voxels) {
    if (nx * ny * nz <= double(max_voxels)) return;
    auto dim = [](double v) { return std::to_string(uint64_t(v)); };
    throw Error(where + ": " + what + " " + dim(nx) + "x" + dim(ny) + "x" + dim(nz) + " is over the dense limit of " +
                std::to_string(max_voxels) + " voxels");
}

VolumeGrid load_volume_grid(const std::filesystem::path& path, const GridLoadOptions& requested) {
    GridLoadOptions options = requested;
    options.max_voxels = std::min(options.max_voxels, k_max_dense_voxels);
    const std::string where = path.string();
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw Error(where + ": volume grid file not found");
    if (!std::filesystem::is_regular_file(path, ec))
        throw Error(where + ": volume grid is not a regular file");
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });

    VolumeGrid g;
    try {
        if (ext == ".vdb")
            g = read_openvdb_grid(path, options.max_voxels);
        else if (ext == ".nvdb")
            g = read_nanovdb_grid(path, options.max_voxels);
        else if (ext == ".bin")
            g = read_raw_grid(path, options);
        else
            throw Error(where + ": unknown volume grid extension '" + ext +
                        "' (expected .vdb, .nvdb or an instant-ngp {W}x{H}x{D}_*.bin)");
    } catch (const std::bad_alloc&) {
        // The raw reader's dense box (the others say their own size): at most max_voxels, 2^28 by default.
        throw Error(where + ": the grid's dense box (up to " + format_bytes(double(options.max_voxels) * 16.0) +
                    ") needs more memory than this machine could allocate: bake it with a smaller --res");
    }
    sanitize(g);
    if (ext == ".bin") pad_clamp_to_edge(g);
    spdlog::debug("{}: volume grid {}x{}x{}", where, g.nx, g.ny, g.nz);
    return g;
}

}  // namespace npt::media
