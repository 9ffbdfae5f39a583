// NanoVDB grid check (media/nanovdb_grid_check.h): a NanoVDB file whose grid bytes carry a count or offset
// that points outside the grid (node counts and offsets, root tiles, child offsets, blind data, the grid
// size) is a one-line error naming the file, the grid and the field, before NanoVDB's checksum or accessors
// follow it (the fuzz finding: an upper-node count of 98 where the file has 1 made the checksum read past the
// buffer). The files are written by our NanoVDB writer and then edited field by field.
#include <gtest/gtest.h>
#include <nanovdb/NanoVDB.h>  // the layout of the fields edited (no NanoVDB code runs here)
#include <openvdb/openvdb.h>

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>

#include "bake/nanovdb_convert.h"
#include "media/volume_grid.h"
#include "test_support.h"

namespace npt::media {
namespace {

namespace fs = std::filesystem;

using TreeData = nanovdb::NanoTree<float>::DataType;
using RootData = nanovdb::NanoRoot<float>::DataType;
using RootTile = RootData::Tile;
using UpperData = nanovdb::NanoUpper<float>::DataType;
using ColorTree = nanovdb::NanoTree<nanovdb::Vec3f>::DataType;

// A density grid with voxels 5000 apart (two upper nodes, two root tiles with children) and a colour grid, as
// bytes, with the positions of the two grids in the file.
struct NanoFile {
    std::string bytes;
    size_t density = 0, color = 0;  // where each grid's bytes start

    template <typename T>
    T get(size_t at) const {
        T v;
        std::memcpy(&v, bytes.data() + at, sizeof(T));
        return v;
    }
    template <typename T>
    NanoFile with(size_t at, T v) const {
        NanoFile f = *this;
        std::memcpy(f.bytes.data() + at, &v, sizeof(T));
        return f;
    }
    size_t tree() const { return density + sizeof(nanovdb::GridData); }
    size_t root() const { return tree() + get<uint64_t>(tree() + offsetof(TreeData, mNodeOffset) + 3 * 8); }
    size_t tile(int i) const { return root() + sizeof(RootData) + i * sizeof(RootTile); }
    size_t first_upper() const {
        return tree() + get<uint64_t>(tree() + offsetof(TreeData, mNodeOffset) + 2 * 8);
    }
};

NanoFile nano_file() {
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->getAccessor().setValue(openvdb::Coord(0, 0, 0), 0.5f);
    density->getAccessor().setValue(openvdb::Coord(5000, 0, 0), 0.25f);
    auto color = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    color->setName("color");
    color->getAccessor().setValue(openvdb::Coord(0, 0, 0), openvdb::Vec3s(1.0f, 0.5f, 0.25f));
    const fs::path path = test::temp_dir() / "source.nvdb";
    bake::write_nanovdb_grids(path, {density, color}, /*full_checksum=*/true);
    std::ifstream in(path, std::ios::binary);
    NanoFile f;
    f.bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    // nanovdb/util/IO.h: a 16-byte segment header, per grid a 176-byte record (file size at 8, name size at
    // 136) and its name, then the grids in order.
    size_t pos = 16;
    uint64_t first_size = 0;
    for (int g = 0; g < 2; ++g) {
        if (g == 0) first_size = f.get<uint64_t>(pos + 8);
        pos += 176 + f.get<uint32_t>(pos + 136);
    }
    f.density = pos;
    f.color = pos + first_size;
    return f;
}

TEST(NanoVdbGridCheck, EveryOffsetAndCountOutsideTheGridIsAnError) {
    const NanoFile good = nano_file();
    const fs::path path = test::temp_dir() / "bad.nvdb";
    test::write_file(path, good.bytes);
    ASSERT_NO_THROW(load_volume_grid(path, {}));
    const auto expect = [&](const NanoFile& f, std::initializer_list<std::string> parts) {
        test::write_file(path, f.bytes);
        test::expect_error_message([&] { load_volume_grid(path, {}); },
                                   {path.string(), "cannot read NanoVDB file: grid '", "(corrupt file)"});
        test::expect_error_message([&] { load_volume_grid(path, {}); }, parts);
    };
    const size_t counts = good.tree() + offsetof(TreeData, mNodeCount);
    const size_t offsets = good.tree() + offsetof(TreeData, mNodeOffset);
    ASSERT_EQ(good.get<uint32_t>(counts + 2 * 4), 2u);  // two upper nodes
    ASSERT_EQ(good.get<uint32_t>(good.root() + offsetof(RootData, mTableSize)), 2u);

    // The fuzz finding: NanoVDB's checksum walked 98 upper nodes from the first one.
    expect(good.with<uint32_t>(counts + 2 * 4, 98), {"grid 'density'", "tree: 98 upper internal nodes"});
    // 2^32 - 1 leaves: an error at once, not a 4 GB table of the nodes reached (a fuzz finding: a timeout).
    expect(good.with<uint32_t>(counts, 0xffffffffu), {"tree: 4294967295 leaf nodes"});
    expect(good.with<uint64_t>(offsets,
                               good.get<uint64_t>(good.density + offsetof(nanovdb::GridData, mGridSize))),
           {"leaf nodes", "do not fit in the grid's"});
    expect(good.with<uint64_t>(offsets + 3 * 8, 0), {"tree: root offset 0"});
    expect(good.with<uint32_t>(good.root() + offsetof(RootData, mTableSize), 1000000),
           {"root: 1000000 tiles"});

    // Child offsets: the root's tiles and an upper node's first child.
    const size_t child0 = good.tile(0) + offsetof(RootTile, child),
                 child1 = good.tile(1) + offsetof(RootTile, child);
    const int64_t off0 = good.get<int64_t>(child0);
    expect(
        good.with<int64_t>(child0, off0 + 32),
        {"root tile, child 0: child offset", "does not point at one of the tree's 2 upper internal nodes"});
    expect(good.with<int64_t>(child1, off0), {"root tile, child 1: upper internal node", "another parent"});
    expect(good.with<int64_t>(child1, 0), {"tree: 2 upper internal nodes counted, 1 reached"});
    const size_t upper = good.first_upper();
    size_t slot = 0;
    for (size_t w = 0; w < 32768 / 64; ++w)
        if (const auto bits = good.get<uint64_t>(upper + offsetof(UpperData, mChildMask) + 8 * w)) {
            slot = 64 * w + size_t(std::countr_zero(bits));
            break;
        }
    const size_t upper_child = upper + offsetof(UpperData, mTable) + 8 * slot;  // a Tile is 8 bytes for float
    expect(good.with<int64_t>(upper_child, good.get<int64_t>(upper_child) + 8),
           {"upper internal node 0, child " + std::to_string(slot), "lower internal nodes"});

    // The grid header: its size, its index in a multi-grid buffer, blind metadata.
    const size_t grid_size = good.density + offsetof(nanovdb::GridData, mGridSize);
    expect(good.with<uint64_t>(grid_size, good.get<uint64_t>(grid_size) + 32), {"grid size field"});
    expect(good.with<uint32_t>(good.density + offsetof(nanovdb::GridData, mGridIndex), 3),
           {"grid index field 3"});
    expect(good.with<uint32_t>(good.density + offsetof(nanovdb::GridData, mBlindMetadataCount), 1)
               .with<int64_t>(good.density + offsetof(nanovdb::GridData, mBlindMetadataOffset), int64_t(1)
                                                                                                    << 40),
           {"blind metadata: 1 records"});

    // The colour grid goes through the same check (vec3f nodes).
    const size_t color_counts = good.color + sizeof(nanovdb::GridData) + offsetof(ColorTree, mNodeCount);
    expect(good.with<uint32_t>(color_counts + 4, 1000000), {"grid 'color'", "1000000 lower internal nodes"});
}

}  // namespace
}  // namespace npt::media
