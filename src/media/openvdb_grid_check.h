// Walks one grid of an OpenVDB file (compression flags, metadata, transform, tree topology and voxel buffers)
// exactly as OpenVDB 10's reader will, before it does: OpenVDB trusts the sizes it reads, and a flipped one
// made it allocate 2^60 bytes or copy a whole block past the end of a node's buffer (bloscFromStream reads an
// uncompressed block of the size the file claims before comparing it with the node's; fixed upstream after
// OpenVDB 10). Every size OpenVDB would use is checked here against the node it fills and the bytes left.
#pragma once

#include <cstdint>
#include <string>

#include "media/vdb_byte_reader.h"

namespace npt::media {

// One grid as its descriptor gives it (openvdb_layout.cpp).
struct VdbGridInfo {
    std::string name;
    uint64_t value_size = 0;    // 4 (float) or 12 (vec3s)
    bool half = false;          // values stored as 16-bit floats (a "_HalfFloat" grid type)
    uint64_t grid_pos = 0, end_pos = 0;
};

// Throws npt::Error ("<file>: cannot read OpenVDB file: grid 'NAME': ...") at the first size that does not
// fit, and when the grid's data does not end where its descriptor says.
void check_openvdb_grid(VdbByteReader& r, const VdbGridInfo& grid);

// Skips a metadata map (the file's or a grid's) consuming exactly the bytes OpenVDB reads: a registered
// fixed-size type reads its own size whatever the stored size says; OpenVDB's delayed-load metadata holds
// blosc blocks whose headers are checked like the voxel blocks'.
void skip_openvdb_metadata(VdbByteReader& r, const std::string& what);

}  // namespace npt::media
