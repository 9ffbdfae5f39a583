// The coarse majorant grid of a volume grid (see MajorantView in volume.h): per block of voxels, the largest
// density over the block's trilinear support, so that blocks with no medium can be skipped.
#pragma once

#include <vector>

#include "media/volume_grid.h"

namespace npt::media {

// Per-block maximum density; writes the block counts per axis.
std::vector<float> build_majorant(const VolumeGrid& grid, int* nx, int* ny, int* nz);

}  // namespace npt::media
