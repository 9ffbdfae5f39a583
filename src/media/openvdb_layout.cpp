#include "media/openvdb_layout.h"

#include <openvdb/version.h>

#include <cstdint>
#include <string>
#include <vector>

#include "media/openvdb_grid_check.h"
#include "media/vdb_byte_reader.h"

namespace npt::media {
namespace {

constexpr int64_t k_openvdb_magic = 0x56444220;  // OPENVDB_MAGIC (" BDV")
// Node-mask compression and per-grid compression flags (OpenVDB 3, 2015) up to the version of the OpenVDB we
// link (224 in OpenVDB 10): the layouts openvdb_grid_check.cpp walks. A newer layout is not guessed at.
constexpr uint32_t k_oldest_version = openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION,
                   k_newest_version = openvdb::OPENVDB_FILE_VERSION;

// "Tree_vec3s_5_4_3" -> "vec3s", as OpenVDB's valueType() names it.
std::string value_type_of(const std::string& tree_type) {
    const size_t a = tree_type.find('_'), b = tree_type.find('_', a + 1);
    return a == std::string::npos ? tree_type : tree_type.substr(a + 1, b - a - 1);
}

}  // namespace

void check_openvdb_layout(const std::string& where) {
    VdbByteReader r(where);
    if (!r.ok() || r.size() < 12) return;  // OpenVDB says "not a VDB file" or "could not open"
    if (r.read<int64_t>("magic") != k_openvdb_magic) return;
    const uint32_t version = r.read<uint32_t>("file version");
    if (version < k_oldest_version)
        r.fail("file format version " + std::to_string(version) +
               " (before OpenVDB 3, 2015) is not supported: save it again with a current OpenVDB");
    if (version > k_newest_version)
        r.fail("file format version " + std::to_string(version) + " is newer than this reader knows (" +
               std::to_string(k_newest_version) + ")");
    r.skip(8, "library version");
    if (r.read<char>("header") == 0)
        r.fail("written as a stream without grid offsets: not supported (write it with openvdb::io::File)");
    r.skip(36, "file UUID");
    skip_openvdb_metadata(r, "file metadata");

    // The grids the reader asks OpenVDB for, walked through once every descriptor is known (density first; a
    // name used twice: each of them).
    struct Wanted {
        VdbGridInfo info;
        std::string type, parent;
    };
    std::vector<Wanted> wanted;
    const int32_t grids = r.read<int32_t>("grid count");
    if (grids < 0) r.fail("grid count " + std::to_string(grids));
    for (int32_t i = 0; i < grids; ++i) {
        const std::string what = "grid descriptor " + std::to_string(i);
        const std::string unique = r.string(what + " name");
        const std::string name = unique.substr(0, unique.find('\x1e'));  // OpenVDB's "name[N]" separator
        std::string type = r.string("grid '" + name + "' type");
        const std::string parent = r.string("grid '" + name + "' instance parent");
        const int64_t grid_pos = r.read<int64_t>("grid '" + name + "' offsets");
        const int64_t block_pos = r.read<int64_t>("grid '" + name + "' offsets");
        const int64_t end_pos = r.read<int64_t>("grid '" + name + "' offsets");
        if (grid_pos < int64_t(r.pos()) || block_pos < grid_pos || end_pos < block_pos)
            r.fail("grid '" + name + "': offsets " + std::to_string(grid_pos) + ", " +
                   std::to_string(block_pos) + ", " + std::to_string(end_pos) + " are out of order");
        if (uint64_t(end_pos) > r.size())
            r.fail("cut short: grid '" + name + "' ends at byte " + std::to_string(end_pos) +
                   ", the file has " + std::to_string(r.size()));
        const uint64_t next = uint64_t(end_pos);

        if (name == "density" || name == "color") {
            Wanted w{VdbGridInfo{name, 0, false, uint64_t(grid_pos), next}, type, parent};
            wanted.insert(name == "density" ? wanted.begin() : wanted.end(), w);
        }
        r.seek(next);
    }
    for (Wanted& w : wanted) {
        VdbGridInfo& g = w.info;
        const std::string half_suffix = "_HalfFloat";
        g.half = w.type.size() > half_suffix.size() &&
                 w.type.compare(w.type.size() - half_suffix.size(), half_suffix.size(), half_suffix) == 0;
        if (g.half) w.type.resize(w.type.size() - half_suffix.size());
        const std::string expected = g.name == "density" ? "float" : "vec3s";
        if (w.type != "Tree_" + expected + "_5_4_3")
            r.fail("grid '" + g.name + "' is a " + value_type_of(w.type) + " grid (" + w.type +
                   "), expected " + expected + " (Tree_" + expected + "_5_4_3)");
        if (!w.parent.empty())
            r.fail("grid '" + g.name + "' is an instance of grid '" + w.parent +
                   "' (shared trees are not supported)");
        g.value_size = g.name == "density" ? 4 : 12;
        check_openvdb_grid(r, g);
    }
}

}  // namespace npt::media
