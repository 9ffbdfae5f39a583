// Checks one NanoVDB grid's bytes, as read from a file, before NanoVDB follows anything in them. NanoVDB 32
// trusts every offset and count in a grid: its checksum (which its validator computes first) walks the node
// arrays by the tree's counts and offsets, and its accessors follow each child offset, so a flipped count
// made the checksum read past the grid's buffer (a fuzz finding).
#pragma once

#include <cstdint>
#include <string>

namespace npt::media {

enum class NanoValueType { f32, vec3f };

// Throws npt::Error("<where>: cannot read NanoVDB file: grid 'NAME': ...") naming the first field that points
// or counts past the grid's `size` bytes: the grid header (size, index, value type, blind metadata and the
// extent of each blind data block), the tree (root offset, root tile table, each level's node offset and
// count) and every child offset (root tiles and internal nodes), which must reach each node of the next level
// exactly once. `data` is NanoVDB's buffer (32-byte aligned).
void check_nanovdb_grid(const std::string& where, const std::string& name, const uint8_t* data, uint64_t size,
                        NanoValueType type);

}  // namespace npt::media
