// Host-side owner of a loaded volume grid (any file format) and the view the per-sample code reads.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "media/grid.h"

namespace npt::media {

struct VolumeGrid {
    std::string source;  // file, for messages
    int nx = 0, ny = 0, nz = 0;
    std::vector<float> density;
    std::vector<Vec3> color;
    Affine3 local_to_index;  // from the volume cube's local space (the glTF node's mesh space) to index space

    GridView view() const { return GridView{nx, ny, nz, density.data(), color.data(), local_to_index}; }
};

// The largest dense grid we allocate (voxels): beyond this a sparse representation is needed (a later issue).
constexpr size_t k_max_dense_voxels = size_t(1) << 28;

// How a file's values become the field (from the scene's `extras.volume`, see docs/formats.md).
struct GridLoadOptions {
    Vec3 local_min{-1.0f}, local_max{1.0f};  // the cube's local bounds: what a raw grid spans
    // Raw grids are instant-ngp output: colours are sRGB-encoded (converted to linear) unless this is false.
    bool raw_color_is_srgb = true;
    // The dense limit; lower only where a smaller grid is all that may be asked for (the fuzz harness: a
    // 2^28-voxel grid from a few bytes is legitimate, and filling it under ASan takes longer than its timeout).
    size_t max_voxels = k_max_dense_voxels;
};

// Throws "<where>: <what> NxxNyxNz is over the dense limit of <max_voxels> voxels" when the box has more voxels;
// the product is taken in double, so no size (up to 2^32 per axis from a file) can wrap it. For the readers.
void check_dense_size(const std::string& where, const std::string& what, double nx, double ny, double nz,
                      size_t max_voxels);

// Loads .vdb (OpenVDB), .nvdb (NanoVDB) or a raw instant-ngp grid ({W}x{H}x{D}_*.bin) by extension and name.
// Negative or NaN densities are clamped to 0 with one warning per file. Throws npt::Error naming file and
// field.
VolumeGrid load_volume_grid(const std::filesystem::path& path, const GridLoadOptions& options);

}  // namespace npt::media
