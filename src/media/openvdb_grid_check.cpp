#include "media/openvdb_grid_check.h"

#include <openvdb/Metadata.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <limits>
#include <map>
#include <vector>

namespace npt::media {
namespace {

// openvdb/io/Compression.h
constexpr uint32_t k_zip = 0x1, k_active_mask = 0x2, k_blosc = 0x4;
// readCompressedValues' per-node flag: which inactive values and selection mask follow.
constexpr int8_t k_one_inactive_no_mask = 2, k_mask_no_inactive = 3, k_mask_one_inactive = 4,
                 k_mask_two_inactive = 5, k_all_values = 6;

std::string decimal(uint64_t v) { return std::to_string(v); }

// A blosc block's 16-byte header: format versions, flags, then (uint32) uncompressed size, block size,
// compressed size including the header. blosc_decompress_ctx takes no source size: it trusts the last one.
// `padded`: OpenVDB's metadata blocks pad less than 128 bytes to 128 before compressing.
void check_blosc_header(VdbByteReader& r, int64_t stored, uint64_t expect, bool padded,
                        const std::string& what) {
    if (stored < 16)
        r.fail(what + ": a blosc block of " + decimal(uint64_t(stored)) + " bytes is shorter than its header");
    std::array<unsigned char, 16> h;
    r.read_bytes(h.data(), h.size(), what);
    uint32_t nbytes, cbytes;
    std::memcpy(&nbytes, h.data() + 4, 4);
    std::memcpy(&cbytes, h.data() + 12, 4);
    if (cbytes > uint64_t(stored))
        r.fail(what + ": a blosc block of " + decimal(uint64_t(stored)) + " bytes claims " + decimal(cbytes));
    if (nbytes != expect && !(padded && nbytes == 128 && expect <= 128))
        r.fail(what + ": a blosc block decompresses to " + decimal(nbytes) + " bytes where " + decimal(expect) +
               " are expected");
    r.skip(uint64_t(stored) - 16, what);
}

// The largest compressed form of `bytes` bytes each codec can produce, which is what OpenVDB's writer
// reserves: zlib's compressBound(), blosc's BLOSC_MAX_OVERHEAD of 16 bytes (bloscToStream writes a block
// that does not shrink uncompressed).
uint64_t max_compressed(uint32_t compression, uint64_t bytes) {
    if (compression & k_blosc) return bytes + 16;
    return bytes + (bytes >> 12) + (bytes >> 14) + (bytes >> 25) + 13;
}

// io::readData of `bytes` bytes: blosc, zip or raw. A compressed block is an int64 size (negative: stored
// uncompressed) and the bytes. OpenVDB allocates the size it reads (bloscFromStream, unzipFromStream), and
// reads an uncompressed block of the claimed size into the node's buffer before comparing: the size is
// checked here against the node, the codec's bound and the bytes left in the grid.
void skip_block(VdbByteReader& r, uint32_t compression, uint64_t bytes, const std::string& what) {
    if (!(compression & (k_blosc | k_zip))) return r.skip(bytes, what);
    const int64_t n = r.read<int64_t>(what + " size");
    if (n <= 0) {
        if (n == std::numeric_limits<int64_t>::min() || uint64_t(-n) != bytes)
            r.fail(what + ": an uncompressed block of " +
                   (n == std::numeric_limits<int64_t>::min() ? "2^63" : decimal(uint64_t(-n))) +
                   " bytes where the node holds " + decimal(bytes));
        return r.skip(bytes, what);
    }
    const uint64_t bound = max_compressed(compression, bytes);
    if (uint64_t(n) > bound)
        r.fail(what + ": a compressed block of " + decimal(uint64_t(n)) + " bytes for " + decimal(bytes) +
               " bytes of values (at most " + decimal(bound) + ")");
    r.need(uint64_t(n), what);
    if (compression & k_blosc) return check_blosc_header(r, n, bytes, false, what);
    r.skip(uint64_t(n), what);  // zlib's uncompress is given the node's size
}

struct Grid {
    const VdbGridInfo& info;
    uint32_t compression = 0;
};

// io::readCompressedValues of a node of `count` values, `active` of them on, with a `count`-bit mask.
void skip_values(VdbByteReader& r, const Grid& g, uint64_t count, uint64_t active, const std::string& what) {
    const int8_t flag = r.read<int8_t>(what + " flags");
    if (flag == k_one_inactive_no_mask || flag == k_mask_one_inactive || flag == k_mask_two_inactive)
        r.skip(g.info.value_size * (flag == k_mask_two_inactive ? 2 : 1), what + " inactive values");
    if (flag == k_mask_no_inactive || flag == k_mask_one_inactive || flag == k_mask_two_inactive)
        r.skip(count / 8, what + " selection mask");
    const uint64_t n = (g.compression & k_active_mask) && flag != k_all_values ? active : count;
    if (g.info.half && n == 0) return;  // io::HalfReader reads nothing for no values
    skip_block(r, g.compression, n * (g.info.half ? g.info.value_size / 2 : g.info.value_size), what);
}

// A node mask of `bits` bits, kept for the node's values and children.
std::vector<uint64_t> read_mask(VdbByteReader& r, uint64_t bits, const std::string& what) {
    std::vector<uint64_t> m(bits / 64);
    r.read_bytes(m.data(), bits / 8, what);
    return m;
}

uint64_t count_on(const std::vector<uint64_t>& m) {
    uint64_t n = 0;
    for (uint64_t w : m) n += uint64_t(std::popcount(w));
    return n;
}

template <typename Fn>
void for_each_on(const std::vector<uint64_t>& m, Fn&& fn) {
    for (size_t w = 0; w < m.size(); ++w)
        for (uint64_t bits = m[w]; bits; bits &= bits - 1) fn(w * 64 + size_t(std::countr_zero(bits)));
}

// The transform: a map type name, then that map's fields (openvdb/math/Maps.h read()).
void skip_transform(VdbByteReader& r, const std::string& where) {
    const std::string type = r.string(where + " transform type");
    static const std::map<std::string, uint64_t> k_map_bytes = {{"AffineMap", 128},
                                                                {"UnitaryMap", 128},
                                                                {"ScaleMap", 5 * 24},
                                                                {"UniformScaleMap", 5 * 24},
                                                                {"TranslationMap", 24},
                                                                {"ScaleTranslateMap", 6 * 24},
                                                                {"UniformScaleTranslateMap", 6 * 24}};
    const auto it = k_map_bytes.find(type);
    if (type == "NonlinearFrustumMap") r.fail(where + ": a non-linear (frustum) transform is not supported");
    if (it == k_map_bytes.end()) r.fail(where + ": unknown transform map '" + type + "'");
    r.skip(it->second, where + " transform");
}

// Appended piece by piece: GCC 12 -O3 reports a false -Wrestrict on "(" + std::to_string(...).
std::string origin_str(const std::array<int32_t, 3>& o) {
    std::string s = "(";
    for (int c = 0; c < 3; ++c) {
        s += std::to_string(o[c]);
        s += c < 2 ? ", " : ")";
    }
    return s;
}

// OpenVDB writes the origins of root tiles and children (4096^3 voxels each) aligned; from an unaligned one
// near 2^31 the coordinates of its last voxels overflow.
void check_origin(VdbByteReader& r, const std::array<int32_t, 3>& origin, const std::string& what) {
    for (const int32_t o : origin)
        if (o % 4096 != 0) r.fail(what + " origin " + origin_str(origin) + " is not a multiple of 4096");
}

}  // namespace

void skip_openvdb_metadata(VdbByteReader& r, const std::string& what) {
    const uint32_t count = r.read<uint32_t>(what + " count");
    for (uint32_t i = 0; i < count; ++i) {
        const std::string item = what + " " + decimal(i);
        const std::string name = r.string(item + " name");
        const std::string type = r.string(item + " type");
        const uint32_t stored = r.read<uint32_t>(item + " size");
        const std::string field = what + " '" + name + "'";
        if (type == "__delayedload") {  // io::DelayedLoadMetadata::readValue
            if (stored == 0) continue;
            const uint64_t start = r.pos();
            const uint32_t leaves = r.read<uint32_t>(field);
            if (leaves > r.size() / 64)  // each leaf's topology takes 64 bytes of the file
                r.fail(field + ": lists " + decimal(leaves) + " leaves, more than the file can hold");
            for (const uint64_t per_leaf : {1, 8}) {  // node flags, then compressed sizes
                const uint32_t bytes = r.read<uint32_t>(field);
                if (per_leaf == 8 && bytes == std::numeric_limits<uint32_t>::max()) break;
                if (bytes == 0)
                    r.skip(leaves * per_leaf, field);
                else {
                    r.need(bytes, field);
                    check_blosc_header(r, bytes, leaves * per_leaf, true, field);
                }
            }
            const uint64_t used = r.pos() - start;  // what OpenVDB counts as read
            if (used >= (uint64_t(1) << 32)) r.fail(field + ": larger than 4 GiB");
            if (used < stored) r.skip(stored - used, field);
            continue;
        }
        uint64_t bytes = stored;  // strings and unregistered types: the stored size
        if (type != "string" && openvdb::Metadata::isRegisteredType(type))
            bytes = openvdb::Metadata::createMetadata(type)->size();  // TypedMetadata reads sizeof(T)
        r.skip(bytes, field);
    }
}

void check_openvdb_grid(VdbByteReader& r, const VdbGridInfo& info) {
    const std::string where = "grid '" + info.name + "'";
    Grid g{info};
    r.limit(info.grid_pos, info.end_pos, where + " (its descriptor's end)");
    g.compression = r.read<uint32_t>(where + " compression");
    skip_openvdb_metadata(r, where + " metadata");
    skip_transform(r, where);

    // Topology: buffer count, root background, root tiles, then each root child (a 32^3 node) with its 16^3
    // children and their 8^3 leaves' masks. The root keeps its children in a map by origin: the buffers
    // below follow that order.
    // Tree::readTopology: one buffer per node since OpenVDB 3 (it warns on stderr and reads on otherwise).
    const uint32_t buffers = r.read<uint32_t>(where + " tree");
    if (buffers != 1)
        r.fail(where + ": " + decimal(buffers) + " buffers per node (only single-buffer trees are supported)");
    r.skip(info.value_size, where + " background");
    const uint32_t tiles = r.read<uint32_t>(where + " root tile count");
    const uint32_t children = r.read<uint32_t>(where + " root child count");
    r.need(uint64_t(tiles) * (12 + info.value_size + 1), where + " root tiles");
    for (uint32_t t = 0; t < tiles; ++t) {
        std::array<int32_t, 3> origin;
        r.read_bytes(origin.data(), 12, where + " root tile");
        check_origin(r, origin, where + ": root tile");
        r.skip(info.value_size + 1, where + " root tile");
    }
    std::map<std::array<int32_t, 3>, std::vector<std::vector<uint64_t>>> root;  // origin -> leaf masks
    for (uint32_t c = 0; c < children; ++c) {
        std::array<int32_t, 3> origin;
        r.read_bytes(origin.data(), 12, where + " root child origin");
        check_origin(r, origin, where + ": root child");
        // OpenVDB would replace the first and leak it.
        if (root.count(origin)) r.fail(where + ": two root children at " + origin_str(origin));
        const auto child5 = read_mask(r, 32768, where + " node mask");
        const auto value5 = read_mask(r, 32768, where + " node mask");
        skip_values(r, g, 32768, count_on(value5), where + " node values");
        std::vector<std::vector<uint64_t>> leaves;
        for_each_on(child5, [&](size_t) {
            const auto child4 = read_mask(r, 4096, where + " node mask");
            const auto value4 = read_mask(r, 4096, where + " node mask");
            skip_values(r, g, 4096, count_on(value4), where + " node values");
            for_each_on(child4, [&](size_t) { leaves.push_back(read_mask(r, 512, where + " leaf mask")); });
        });
        root[origin] = std::move(leaves);
    }
    // Buffers: each leaf's mask again (OpenVDB skips it in a seekable file and reads it otherwise: the two
    // must agree) and its values.
    for (const auto& [origin, leaves] : root)
        for (const auto& mask : leaves) {
            if (read_mask(r, 512, where + " leaf mask") != mask)
                r.fail(where + ": a leaf's mask in the voxel buffers differs from the one in its topology");
            skip_values(r, g, 512, count_on(mask), where + " voxel values");
        }
    if (r.pos() != info.end_pos)
        r.fail(where + ": its data ends at byte " + decimal(r.pos()) + ", its descriptor says " +
               decimal(info.end_pos));
    r.limit(info.end_pos, r.size(), "the file");
}

}  // namespace npt::media
