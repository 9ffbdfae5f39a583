// Reads a NanoVDB file (float grid `density`, optional Vec3f grid `color`) into a dense VolumeGrid over the
// density's active-voxel bounding box, with local_to_index taken from the density grid's own map.
#pragma once

#include <filesystem>

#include "media/volume_grid.h"

namespace npt::media {

// Values are returned as stored (load_volume_grid clamps them). Throws npt::Error naming the file and the
// grid.
// A density box over max_voxels is an error.
VolumeGrid read_nanovdb_grid(const std::filesystem::path& path, size_t max_voxels = k_max_dense_voxels);

}  // namespace npt::media
