// OpenVDB grids to a NanoVDB file, for the tests that need .nvdb files of their own making: NanoVDB's
// converter is among the slowest templates we compile (minutes per file under the sanitizers), so it is
// instantiated once, in vdb_writer.cpp, beside the bake writer that uses it.
#pragma once

#include <openvdb/openvdb.h>

#include <filesystem>

namespace npt::bake {

// Writes the grids (FloatGrid or Vec3SGrid; another type is an npt::Error) in order as one uncompressed
// NanoVDB file. `full_checksum`: a CRC over all voxel data (what write_nvdb writes); otherwise NanoVDB's
// default partial checksum (header and upper nodes).
void write_nanovdb_grids(const std::filesystem::path& path, const openvdb::GridPtrVec& grids, bool full_checksum);

}  // namespace npt::bake
