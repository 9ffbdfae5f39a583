// Checks a NanoVDB file's container (segment headers, grid metadata and names, each segment's grid bytes)
// before NanoVDB's own reader parses it: that reader allocates the name size a file claims and copies the
// name with strlen, so a name without its terminating zero read past the buffer, and a cut file left
// uninitialised sizes behind.
#pragma once

#include <string>

namespace npt::media {

// Throws npt::Error("<where>: cannot read NanoVDB file: ...") when a header, a metadata record, a name or a
// segment's grids run past the end of the file, a name lacks its terminating zero, a segment has another major
// format version than the NanoVDB we build with, or a segment is compressed (only uncompressed files are
// read). A wrong magic number is left to NanoVDB, which reports it.
void check_nanovdb_layout(const std::string& where);

}  // namespace npt::media
