// OpenVDB file check (media/openvdb_layout.h, openvdb_grid_check.h): a file OpenVDB wrote passes and loads as
// before; the same file cut at any byte, descriptors whose offsets point outside the file or run backwards,
// block sizes beyond their node, their codec's bound or their grid, and broken blosc headers and root
// origins are one-line errors before OpenVDB reads or allocates anything from them.
#include "media/openvdb_layout.h"

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include "media/volume_grid.h"
#include "test_support.h"

namespace npt::media {
namespace {

namespace fs = std::filesystem;

std::string two_grid_file() {
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->getAccessor().setValue(openvdb::Coord(1, 2, 3), 0.5f);
    auto color = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    color->setName("color");
    color->getAccessor().setValue(openvdb::Coord(1, 2, 3), openvdb::Vec3s(1, 0, 0));
    const fs::path path = test::temp_dir() / "whole.vdb";
    openvdb::io::File(path.string()).write({density, color});
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Byte offset of grid `name`'s three int64 offsets in its descriptor.
size_t offsets_at(const std::string& bytes, const std::string& name) {
    const std::string key = std::string(1, char(name.size())) + std::string(3, '\0') + name;
    size_t at = bytes.find(key);
    EXPECT_NE(at, std::string::npos);
    at += key.size();
    for (int s = 0; s < 2; ++s) {  // type, instance parent
        uint32_t n;
        std::memcpy(&n, bytes.data() + at, 4);
        at += 4 + n;
    }
    return at;
}

TEST(OpenVdbLayout, WholeFilePassesEveryCutIsAnError) {
    const std::string bytes = two_grid_file();
    const fs::path path = test::temp_dir() / "cut.vdb";
    test::write_file(path, bytes);
    EXPECT_NO_THROW(check_openvdb_layout(path.string()));
    EXPECT_NO_THROW(load_volume_grid(path, {}));
    // Every cut from the end of the magic number on: the header, the file metadata, each descriptor, each
    // grid.
    for (size_t n = 12; n < bytes.size(); n += (n < 400 || n + 64 > bytes.size()) ? 1 : 37) {
        test::write_file(path, bytes.substr(0, n));
        test::expect_error_message([&] { check_openvdb_layout(path.string()); },
                                   {path.string(), "cannot read OpenVDB file: cut short"});
    }
    test::write_file(path, bytes.substr(0, bytes.size() - 1));
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "cut short: grid 'color' ends at byte"});
}

TEST(OpenVdbLayout, OffsetsOutsideTheFileOrBackwards) {
    const std::string bytes = two_grid_file();
    const fs::path path = test::temp_dir() / "bad.vdb";
    const size_t at = offsets_at(bytes, "density");
    const auto with_offset = [&](int which, int64_t v) {
        std::string b = bytes;
        std::memcpy(b.data() + at + 8 * which, &v, 8);
        test::write_file(path, b);
    };
    with_offset(2, int64_t(bytes.size()) + 1000);  // end
    test::expect_error_message([&] { check_openvdb_layout(path.string()); },
                               {path.string(), "grid 'density' ends at byte"});
    with_offset(0, 3);  // grid data inside the header
    test::expect_error_message([&] { check_openvdb_layout(path.string()); },
                               {path.string(), "grid 'density'", "out of order"});
    with_offset(1, -5);  // blocks before the grid
    test::expect_error_message([&] { check_openvdb_layout(path.string()); },
                               {path.string(), "grid 'density'", "out of order"});
}

// The node-by-node walk (openvdb_grid_check.h) must end exactly where OpenVDB's writer says each grid ends,
// whatever OpenVDB chose to write: every compression, half floats, tiles at the root and in nodes, inactive
// values other than the background (the per-node flags that add values and selection masks), other grids.
TEST(OpenVdbLayout, EveryWayOpenVdbWritesAGridPasses) {
    openvdb::initialize();
    const fs::path path = test::temp_dir() / "variants.vdb";
    const uint32_t compressions[] = {openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK,
                                     openvdb::io::COMPRESS_BLOSC,
                                     openvdb::io::COMPRESS_ZIP,
                                     openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK,
                                     openvdb::io::COMPRESS_ACTIVE_MASK,
                                     openvdb::io::COMPRESS_NONE};
    for (const uint32_t compression : compressions)
        for (const bool half : {false, true}) {
            auto density = openvdb::FloatGrid::create(0.0f);
            density->setName("density");
            density->setSaveFloatAsHalf(half);
            auto acc = density->getAccessor();
            for (int i = 0; i < 300; ++i)
                acc.setValue(openvdb::Coord(i % 17, i / 17, i % 5), 0.01f * float(i));
            acc.setValueOff(openvdb::Coord(3, 3, 3), -2.0f);  // an inactive value that is not the background
            acc.setValueOff(openvdb::Coord(4, 3, 3), 5.0f);   // and a second one
            density->fill(openvdb::CoordBBox(openvdb::Coord(4096), openvdb::Coord(4096 + 4095)),
                          1.0f);                                                                // root tile
            density->fill(openvdb::CoordBBox(openvdb::Coord(-128), openvdb::Coord(-1)), 0.5f);  // node tiles
            density->tree().setValue(openvdb::Coord(-200, 900, 40000), 2.0f);  // another root child
            auto color = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
            color->setName("color");
            color->setSaveFloatAsHalf(half);
            color->tree().setValue(openvdb::Coord(1, 2, 3), openvdb::Vec3s(1, 0, 0));
            auto other = openvdb::Int32Grid::create(7);
            other->setName("labels");
            other->tree().setValue(openvdb::Coord(9), 3);
            openvdb::io::File file(path.string());
            file.setCompression(compression);
            file.write({other, density, color});
            EXPECT_NO_THROW(check_openvdb_layout(path.string()))
                << "compression " << compression << " half " << half;
        }
}

// A density grid of one full leaf at (8..15, 0..7, 0..7) with smooth values (zip shrinks them to far less
// than the 2048 bytes of the leaf) and a colour grid, written with `compression`, the density grid first or
// last.
std::string one_leaf_file(uint32_t compression, bool density_last = false) {
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    auto acc = density->getAccessor();
    for (int i = 0; i < 512; ++i) acc.setValue(openvdb::Coord(8 + i % 8, i / 8 % 8, i / 64), 0.5f);
    auto color = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    color->setName("color");
    color->getAccessor().setValue(openvdb::Coord(8, 0, 0), openvdb::Vec3s(1, 0, 0));
    const fs::path path = test::temp_dir() / "leaf.vdb";
    openvdb::io::File file(path.string());
    file.setCompression(compression);
    if (density_last)
        file.write({color, density});
    else
        file.write({density, color});
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

int64_t int64_at(const std::string& bytes, size_t at) {
    int64_t v;
    std::memcpy(&v, bytes.data() + at, 8);
    return v;
}

// The leaf's compressed block is the last thing in the density grid: its int64 size is the one whose bytes
// run exactly to the grid's end.
size_t leaf_block_size_at(const std::string& bytes) {
    const int64_t end = int64_at(bytes, offsets_at(bytes, "density") + 16);
    for (int64_t at = end - 9; at > 0; --at)
        if (int64_at(bytes, size_t(at)) == end - at - 8) return size_t(at);
    ADD_FAILURE() << "no block size runs to the end of grid 'density' at " << end;
    return 0;
}

// A valid file loads, and the check leaves what OpenVDB reads alone: the same voxels come out.
void expect_leaf_loads(const fs::path& path) {
    const VolumeGrid g = load_volume_grid(path, {});
    ASSERT_EQ(g.nx * g.ny * g.nz, 512);
    for (const float d : g.density) EXPECT_EQ(d, 0.5f);
}

TEST(OpenVdbLayout, ZipBlockSizesAreCheckedAgainstTheNodeTheCodecAndTheGrid) {
    const std::string bytes = one_leaf_file(openvdb::io::COMPRESS_ZIP);
    const fs::path path = test::temp_dir() / "zip.vdb";
    test::write_file(path, bytes);
    expect_leaf_loads(path);
    const size_t at = leaf_block_size_at(bytes);
    const int64_t stored = int64_at(bytes, at);
    ASSERT_LT(stored, 1900) << "the test needs a leaf that zip compresses";
    const auto with_size = [&](int64_t v) {
        std::string b = bytes;
        std::memcpy(b.data() + at, &v, 8);
        test::write_file(path, b);
    };
    with_size(int64_t(1) << 60);  // what made OpenVDB allocate 2^60 bytes
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "grid 'density' voxel values: a compressed block of " +
                                                   std::to_string(int64_t(1) << 60) + " bytes for 2048"});
    with_size(stored + 100);  // within zlib's bound for 2048 bytes, past the grid's end (the colour grid)
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "past the end of grid 'density'"});
    with_size(-2052);  // an uncompressed block larger than the leaf: OpenVDB copied it past the buffer
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "an uncompressed block of 2052 bytes where the node holds 2048"});
    with_size(std::numeric_limits<int64_t>::min());
    test::expect_error_message([&] { load_volume_grid(path, {}); }, {path.string(), "2^63 bytes"});
    // The file cut inside the last block of its last grid, that grid's descriptor moved with the cut (the
    // next descriptor starts at the end of a grid, so only the last one can end early and leave the file
    // consistent).
    std::string cut = one_leaf_file(openvdb::io::COMPRESS_ZIP, /*density_last=*/true);
    const size_t end_at = offsets_at(cut, "density") + 16;
    const int64_t end = int64_at(cut, end_at) - 5;
    std::memcpy(cut.data() + end_at, &end, 8);
    test::write_file(path, cut.substr(0, size_t(end)));
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "cut short: grid 'density' voxel values needs"});
}

TEST(OpenVdbLayout, BloscHeadersAreCheckedBeforeBloscTrustsThem) {
    const std::string bytes = one_leaf_file(openvdb::io::COMPRESS_BLOSC);
    const fs::path path = test::temp_dir() / "blosc.vdb";
    test::write_file(path, bytes);
    expect_leaf_loads(path);
    const size_t at = leaf_block_size_at(bytes) + 8;  // the blosc header
    const auto with_u32 = [&](size_t field, uint32_t v) {
        std::string b = bytes;
        std::memcpy(b.data() + at + field, &v, 4);
        test::write_file(path, b);
    };
    with_u32(4, 4096);  // uncompressed size: blosc would write it into the leaf's 2048 bytes
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "decompresses to 4096 bytes where 2048 are expected"});
    with_u32(12, 1u << 30);  // compressed size: blosc reads that much from OpenVDB's buffer
    test::expect_error_message([&] { load_volume_grid(path, {}); }, {path.string(), "claims 1073741824"});
}

// Root tiles and children: OpenVDB writes them aligned to 4096 and each child once.
TEST(OpenVdbLayout, RootOriginsMustBeAlignedAndUnique) {
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->tree().setValue(openvdb::Coord(1, 2, 3), 1.0f);
    density->tree().setValue(openvdb::Coord(5 * 4096 + 1, 3 * 4096, -7 * 4096), 1.0f);
    const fs::path path = test::temp_dir() / "origins.vdb";
    openvdb::io::File(path.string()).write({density});
    std::ifstream in(path, std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    EXPECT_NO_THROW(check_openvdb_layout(path.string()));
    const int32_t second[3] = {5 * 4096, 3 * 4096, -7 * 4096};
    const size_t at = bytes.find(std::string(reinterpret_cast<const char*>(second), 12));
    ASSERT_NE(at, std::string::npos);
    std::string b = bytes;
    const int32_t unaligned = 5 * 4096 + 8;
    std::memcpy(b.data() + at, &unaligned, 4);
    test::write_file(path, b);
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "root child origin (20488, 12288, -28672) is not a multiple"});
    b = bytes;
    std::memset(b.data() + at, 0, 12);  // the first child's origin
    test::write_file(path, b);
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "two root children at (0, 0, 0)"});
}

// Active voxels 2^32 apart: the box's width does not fit OpenVDB's int32 (it overflowed in bbox.dim()).
TEST(OpenVdbLayout, AWholeIndexSpaceBoxIsOverTheDenseLimit) {
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->tree().setValue(openvdb::Coord(std::numeric_limits<int32_t>::min(), 0, 0), 1.0f);
    density->tree().setValue(openvdb::Coord(std::numeric_limits<int32_t>::max(), 0, 0), 1.0f);
    const fs::path path = test::temp_dir() / "wide.vdb";
    openvdb::io::File(path.string()).write({density});
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "active bounding box 4294967296x1x1 is over the dense limit"});
}

// OpenVDB warned on stderr ("multi-buffer trees are no longer supported") and read on.
TEST(OpenVdbLayout, OneBufferPerNode) {
    std::string bytes = one_leaf_file(openvdb::io::COMPRESS_ZIP);
    // Buffer count 1, background 0, no root tiles, one root child at (0, 0, 0).
    const uint32_t topology[7] = {1, 0, 0, 1, 0, 0, 0};
    const size_t at = bytes.find(std::string(reinterpret_cast<const char*>(topology), sizeof topology));
    ASSERT_NE(at, std::string::npos);
    bytes[at] = 2;
    const fs::path path = test::temp_dir() / "buffers.vdb";
    test::write_file(path, bytes);
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "grid 'density': 2 buffers per node"});
}

// A 512^3 active tile is 2^27 voxels, under the default dense limit; a caller's lower limit (the fuzz harness's:
// filling such a grid under ASan outlasted libFuzzer's timeout) is an error before anything is allocated.
TEST(OpenVdbLayout, TheCallersDenseLimitIsCheckedBeforeFilling) {
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(511)), 1.0f);
    const fs::path path = test::temp_dir() / "tile.vdb";
    openvdb::io::File(path.string()).write({density});
    GridLoadOptions options;
    options.max_voxels = size_t(1) << 22;
    test::expect_error_message([&] { load_volume_grid(path, options); },
                               {path.string(), "512x512x512 is over the dense limit of 4194304 voxels"});
}

TEST(OpenVdbLayout, NotAVdbFileIsLeftToOpenVdb) {
    const fs::path path = test::temp_dir() / "text.vdb";
    test::write_file(path, "definitely not a grid");
    EXPECT_NO_THROW(check_openvdb_layout(path.string()));
    test::expect_error_message([&] { load_volume_grid(path, {}); }, {path.string(), "not a VDB file"});
}

}  // namespace
}  // namespace npt::media
