#include "media/volume_grid.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

#include "core/error.h"
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

}  // namespace

VolumeGrid load_volume_grid(const std::filesystem::path& path, const GridLoadOptions& options) {
    const std::string where = path.string();
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw Error(where + ": volume grid file not found");
    if (!std::filesystem::is_regular_file(path, ec))
        throw Error(where + ": volume grid is not a regular file");
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });

    VolumeGrid g;
    if (ext == ".vdb")
        g = read_openvdb_grid(path);
    else if (ext == ".nvdb")
        g = read_nanovdb_grid(path);
    else if (ext == ".bin")
        g = read_raw_grid(path, options);
    else
        throw Error(where + ": unknown volume grid extension '" + ext +
                    "' (expected .vdb, .nvdb or an instant-ngp {W}x{H}x{D}_*.bin)");
    sanitize(g);
    spdlog::debug("{}: volume grid {}x{}x{}", where, g.nx, g.ny, g.nz);
    return g;
}

}  // namespace npt::media
