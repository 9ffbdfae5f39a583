// Checks an OpenVDB file's container (header, file metadata, grid descriptors and the byte range of each
// grid) before OpenVDB reads it. OpenVDB 10 reads sizes from a stream without checking that the read
// succeeded, so a file cut short made it allocate whatever was in memory (terabytes) instead of failing.
#pragma once

#include <string>

namespace npt::media {

// Throws npt::Error("<where>: cannot read OpenVDB file: ...") when a string, a metadata value or a grid runs
// past the end of the file. Files that are not VDB files, format versions before 218 (2013) and streams
// without grid offsets are left to OpenVDB, which reports them.
void check_openvdb_layout(const std::string& where);

}  // namespace npt::media
