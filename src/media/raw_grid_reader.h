// Reads instant-ngp's raw RGBA-sigma grid ({W}x{H}x{D}_*.bin: float32 R, G, B, sigma per voxel, x fastest,
// the file's first row the top one) into a cell-centred dense VolumeGrid spanning the volume cube's local
// box.
#pragma once

#include <array>
#include <filesystem>

#include "media/volume_grid.h"

namespace npt::media {

// The {W}x{H}x{D} token of a raw grid's file name: the stem's first '_'-separated part that reads as
// <digits>x<digits>x<digits>. Throws npt::Error naming the file when there is none or a number overflows.
std::array<size_t, 3> parse_raw_grid_dims(const std::filesystem::path& path);

// Sigma is stored as instant-ngp wrote it (per unit length of instant-ngp's unit cube; see docs/formats.md
// for the scale the renderer applies). Throws npt::Error naming the file.
VolumeGrid read_raw_grid(const std::filesystem::path& path, const GridLoadOptions& options);

}  // namespace npt::media
