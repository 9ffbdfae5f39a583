// Checks an OpenVDB file before OpenVDB reads it: the container (header, file metadata, grid descriptors and
// each grid's byte range), and the grids named density and color node by node (openvdb_grid_check.h). OpenVDB
// 10 trusts the sizes it reads: a file cut short made it allocate whatever was in memory (terabytes), a
// flipped size made it write past a node's buffer.
#pragma once

#include <string>

namespace npt::media {

// Throws npt::Error("<where>: cannot read OpenVDB file: ...") at the first size that does not fit, for format
// versions other than 222..224 (OpenVDB 3 to the one we link), streams without grid offsets, and a density or color grid
// of another type or shared with another grid. Files that are not VDB files are left to OpenVDB.
void check_openvdb_layout(const std::string& where);

}  // namespace npt::media
