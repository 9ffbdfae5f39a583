// Reads an OpenVDB file (FloatGrid `density`, optional Vec3SGrid `color`) into a dense VolumeGrid over the
// density's active-voxel bounding box, with local_to_index taken from the density grid's own transform.
#pragma once

#include <filesystem>

#include "media/volume_grid.h"

namespace npt::media {

// Values are returned as stored (no clamping of negative or NaN densities: load_volume_grid does that).
// Throws npt::Error naming the file and the grid.
// A density box over max_voxels is an error.
VolumeGrid read_openvdb_grid(const std::filesystem::path& path, size_t max_voxels = k_max_dense_voxels);

// openvdb::initialize(), once per process, safe from several threads: every use of OpenVDB (this reader,
// the bake writer) calls it first.
void ensure_openvdb_initialized();

}  // namespace npt::media
