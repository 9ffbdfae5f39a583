#include "media/nanovdb_grid_check.h"

// clang-format off
#include "media/nanovdb_headers.h"  // first: NanoVDB with its own asserts off
// clang-format on

#include <vector>

#include "core/error.h"

namespace npt::media {
namespace {

std::string str(uint64_t v) { return std::to_string(v); }

// True when `count` items of `bytes` bytes from byte `at` lie inside a buffer of `size` bytes (no overflow).
bool fits(uint64_t size, uint64_t at, uint64_t count, uint64_t bytes) {
    return at <= size && count <= (size - at) / bytes;
}

// `base` + `offset` (base <= size) as a byte position in [0, size]; false when it falls outside.
bool add_offset(uint64_t base, int64_t offset, uint64_t size, uint64_t& out) {
    if (offset < 0) {
        const uint64_t back = uint64_t(-(offset + 1)) + 1;  // |offset| without overflow at INT64_MIN
        if (back > base) return false;
        out = base - back;
        return true;
    }
    if (uint64_t(offset) > size - base) return false;
    out = base + uint64_t(offset);
    return true;
}

constexpr const char* k_level[3] = {"leaf", "lower internal", "upper internal"};

template <typename ValueT>
class GridCheck {
    using TreeData = typename nanovdb::NanoTree<ValueT>::DataType;
    using RootData = typename nanovdb::NanoRoot<ValueT>::DataType;
    using Tile = typename RootData::Tile;
    using UpperData = typename nanovdb::NanoUpper<ValueT>::DataType;
    using LowerData = typename nanovdb::NanoLower<ValueT>::DataType;
    static constexpr uint64_t k_align = NANOVDB_DATA_ALIGNMENT;
    static constexpr uint64_t k_tree_at = sizeof(nanovdb::GridData);  // the tree header follows the grid's
    static constexpr uint64_t k_node_bytes[3] = {sizeof(nanovdb::NanoLeaf<ValueT>),
                                                 sizeof(nanovdb::NanoLower<ValueT>),
                                                 sizeof(nanovdb::NanoUpper<ValueT>)};
    static_assert(sizeof(nanovdb::NanoGrid<ValueT>) == sizeof(nanovdb::GridData));

  public:
    GridCheck(std::string prefix, const uint8_t* data, uint64_t size)
        : m_prefix(std::move(prefix)), m_data(data), m_size(size) {}

    void run() {
        check_header();
        check_blind_data();
        check_tree();
        walk();
    }

  private:
    [[noreturn]] void fail(const std::string& why) const { throw Error(m_prefix + why + " (corrupt file)"); }

    template <typename T>
    const T& at(uint64_t pos) const {
        return *reinterpret_cast<const T*>(m_data + pos);  // pos is checked and 32-byte aligned
    }

    void check_header() {
        if (!m_data || m_size < k_tree_at + sizeof(TreeData))
            fail("its " + str(m_size) + " bytes are fewer than the grid and tree headers take (" +
                 str(k_tree_at + sizeof(TreeData)) + ")");
        if (reinterpret_cast<uintptr_t>(m_data) % k_align) fail("buffer not 32-byte aligned");
        const auto& g = at<nanovdb::GridData>(0);
        if (g.mMagic != NANOVDB_MAGIC_NUMBER) fail("the grid header's magic number is wrong");
        // NanoVDB bounds its reads by this field, we by the bytes read.
        if (g.mGridSize != m_size)
            fail("grid size field " + str(g.mGridSize) + " differs from the " + str(m_size) +
                 " bytes of its file record");
        // GridHandle::grid() steps grid size bytes on until it meets index 0.
        if (g.mGridIndex != 0 || g.mGridCount == 0)
            fail("grid index field " + str(g.mGridIndex) + " of " + str(g.mGridCount) +
                 " (a grid read alone is 0 of at least 1)");
        if (g.mGridType != nanovdb::mapToGridType<ValueT>())
            fail("grid type field " + str(uint32_t(g.mGridType)) + " differs from its file record's " +
                 str(uint32_t(nanovdb::mapToGridType<ValueT>())));
    }

    // We read no blind data, but NanoVDB follows these offsets (a long grid name, point data): each record
    // and the first element count bytes of its data lie in the grid (elements are at least a byte).
    void check_blind_data() {
        const auto& g = at<nanovdb::GridData>(0);
        const uint64_t count = g.mBlindMetadataCount, bytes = sizeof(nanovdb::GridBlindMetaData);
        if (count == 0) return;
        uint64_t meta_at = 0;
        if (!add_offset(0, g.mBlindMetadataOffset, m_size, meta_at) || meta_at % k_align ||
            !fits(m_size, meta_at, count, bytes))
            fail("blind metadata: " + str(count) + " records of " + str(bytes) + " bytes at offset " +
                 std::to_string(g.mBlindMetadataOffset) + " do not fit in the grid's " + str(m_size) +
                 " bytes");
        for (uint64_t i = 0; i < count; ++i) {
            const uint64_t rec_at = meta_at + i * bytes;
            const auto& b = at<nanovdb::GridBlindMetaData>(rec_at);
            uint64_t data_at = 0;
            if (!add_offset(rec_at, b.mByteOffset, m_size, data_at) ||
                !fits(m_size, data_at, b.mElementCount, 1))
                fail("blind data " + str(i) + ": " + str(b.mElementCount) + " elements at offset " +
                     std::to_string(b.mByteOffset) + " from its record do not fit in the grid's " +
                     str(m_size) + " bytes");
        }
    }

    void check_tree() {
        const auto& t = at<TreeData>(k_tree_at);
        const uint64_t left = m_size - k_tree_at;
        // The checksum covers the tree header and the root as if the root followed the tree header; it does
        // when its offset is at least the header's size.
        const uint64_t root_off = t.mNodeOffset[3];
        if (root_off < sizeof(TreeData) || root_off % k_align || !fits(left, root_off, 1, sizeof(RootData)))
            fail("tree: root offset " + str(root_off) + " is not inside the grid's " + str(m_size) +
                 " bytes");
        m_root_at = k_tree_at + root_off;
        const uint32_t tiles = at<RootData>(m_root_at).mTableSize;
        if (!fits(m_size, m_root_at + sizeof(RootData), tiles, sizeof(Tile)))
            fail("root: " + str(tiles) + " tiles of " + str(sizeof(Tile)) + " bytes from offset " +
                 str(m_root_at + sizeof(RootData)) + " do not fit in the grid's " + str(m_size) + " bytes");
        for (int level = 0; level < 3; ++level) {
            const uint64_t count = t.mNodeCount[level], off = t.mNodeOffset[level];
            m_count[level] = count;
            if (count == 0) continue;
            if (off % k_align || !fits(left, off, count, k_node_bytes[level]))
                fail("tree: " + str(count) + " " + k_level[level] + " nodes of " + str(k_node_bytes[level]) +
                     " bytes from offset " + str(off) + " do not fit in the grid's " + str(m_size) +
                     " bytes");
            m_first[level] = k_tree_at + off;
            // Only now: sized before the check, a count of 2^32 - 1 was a 4 GB table (a fuzz finding).
            m_seen[level].assign(count, 0);
        }
    }

    // The position of the node of `level` that `offset` from `parent_at` points at, which must be one of that
    // level's nodes and not yet reached from another parent.
    uint64_t child(uint64_t parent_at, int64_t offset, int level, const char* parent, uint64_t parent_index,
                   uint64_t slot) {
        uint64_t pos = 0, index = 0;
        const uint64_t bytes = k_node_bytes[level];
        const bool ok = add_offset(parent_at, offset, m_size, pos) && m_count[level] > 0 &&
                        pos >= m_first[level] && (pos - m_first[level]) % bytes == 0 &&
                        (index = (pos - m_first[level]) / bytes) < m_count[level];
        if (!ok || m_seen[level][index]) {
            const std::string from = std::string(parent) +
                                     (parent_index == ~uint64_t(0) ? "" : " node " + str(parent_index)) +
                                     ", child " + str(slot);
            if (!ok)
                fail(from + ": child offset " + std::to_string(offset) +
                     " does not point at one of the tree's " + str(m_count[level]) + " " + k_level[level] +
                     " nodes");
            fail(from + ": " + k_level[level] + " node " + str(index) + " has another parent too");
        }
        m_seen[level][index] = 1;
        ++m_reached[level];
        return pos;
    }

    template <typename DataT, int Level>
    void walk_internal(uint64_t node_at) {
        const auto& d = at<DataT>(node_at);
        const uint64_t index = (node_at - m_first[Level]) / k_node_bytes[Level];
        for (auto it = d.mChildMask.beginOn(); it; ++it) {
            const uint64_t c = child(node_at, d.mTable[*it].child, Level - 1, k_level[Level], index, *it);
            if constexpr (Level == 2) walk_internal<LowerData, 1>(c);
        }
    }

    // Every child offset of the root and of the internal nodes, as NanoVDB's node manager (which fills one
    // slot per child in arrays of the tree's node counts) and accessors follow them.
    void walk() {
        const auto& root = at<RootData>(m_root_at);
        for (uint32_t i = 0; i < root.mTableSize; ++i) {
            const auto& tile = at<Tile>(m_root_at + sizeof(RootData) + uint64_t(i) * sizeof(Tile));
            if (!tile.isChild()) continue;
            walk_internal<UpperData, 2>(child(m_root_at, tile.child, 2, "root tile", ~uint64_t(0), i));
        }
        for (int level = 2; level >= 0; --level)
            if (m_reached[level] != m_count[level])
                fail("tree: " + str(m_count[level]) + " " + k_level[level] + " nodes counted, " +
                     str(m_reached[level]) + " reached from the root");
    }

    std::string m_prefix;
    const uint8_t* m_data;
    uint64_t m_size;
    uint64_t m_root_at = 0;
    uint64_t m_first[3] = {}, m_count[3] = {}, m_reached[3] = {};
    std::vector<uint8_t> m_seen[3];
};

}  // namespace

void check_nanovdb_grid(const std::string& where, const std::string& name, const uint8_t* data, uint64_t size,
                        NanoValueType type) {
    std::string prefix = where + ": cannot read NanoVDB file: grid '" + name + "': ";
    if (type == NanoValueType::f32)
        GridCheck<float>(std::move(prefix), data, size).run();
    else
        GridCheck<nanovdb::Vec3f>(std::move(prefix), data, size).run();
}

}  // namespace npt::media
