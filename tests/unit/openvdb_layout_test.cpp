// OpenVDB container check (media/openvdb_layout.h): a file OpenVDB wrote passes; the same file cut at any
// byte, and descriptors whose offsets point outside the file or run backwards, are one-line errors before
// OpenVDB reads a size from the missing bytes.
#include "media/openvdb_layout.h"

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
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

TEST(OpenVdbLayout, NotAVdbFileIsLeftToOpenVdb) {
    const fs::path path = test::temp_dir() / "text.vdb";
    test::write_file(path, "definitely not a grid");
    EXPECT_NO_THROW(check_openvdb_layout(path.string()));
    test::expect_error_message([&] { load_volume_grid(path, {}); }, {path.string(), "not a VDB file"});
}

}  // namespace
}  // namespace npt::media
