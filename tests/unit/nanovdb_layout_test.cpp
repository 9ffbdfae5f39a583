// NanoVDB container check (media/nanovdb_layout.h): a file NanoVDB wrote passes; a name without its zero
// byte (NanoVDB's reader ran strlen past it), a claimed name or grid size beyond the file, another major
// format version and a compressed segment are one-line errors; a file cut anywhere is an error, never a read
// past a buffer.
#include "media/nanovdb_layout.h"

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "bake/nanovdb_convert.h"
#include "media/volume_grid.h"
#include "test_support.h"

namespace npt::media {
namespace {

namespace fs = std::filesystem;

std::string nanovdb_file() {
    openvdb::initialize();
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->getAccessor().setValue(openvdb::Coord(1, 2, 3), 0.5f);
    const fs::path path = test::temp_dir() / "whole.nvdb";
    bake::write_nanovdb_grids(path, {density}, /*full_checksum=*/true);
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

constexpr size_t k_record = 16;  // the first grid's record follows the 16-byte segment header

TEST(NanoVdbLayout, WholeFilePassesBrokenRecordsAreErrors) {
    const std::string bytes = nanovdb_file();
    const fs::path path = test::temp_dir() / "bad.nvdb";
    test::write_file(path, bytes);
    EXPECT_NO_THROW(check_nanovdb_layout(path.string()));
    EXPECT_NO_THROW(load_volume_grid(path, {}));

    uint32_t name_size;
    std::memcpy(&name_size, bytes.data() + k_record + 136, 4);
    ASSERT_EQ(name_size, 8u);  // "density" and its zero
    std::string b = bytes;
    b[k_record + 176 + name_size - 1] = 'x';
    test::write_file(path, b);
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "does not end in a zero"});

    b = bytes;
    const uint32_t huge = 0xfffffff0u;
    std::memcpy(b.data() + k_record + 136, &huge, 4);
    test::write_file(path, b);
    test::expect_error_message([&] { load_volume_grid(path, {}); }, {path.string(), "does not fit"});

    b = bytes;
    const uint64_t too_big = uint64_t(bytes.size()) * 2;
    std::memcpy(b.data() + k_record + 8, &too_big, 8);  // the grid's bytes in the file
    test::write_file(path, b);
    test::expect_error_message([&] { load_volume_grid(path, {}); }, {path.string(), "cut short"});

    b = bytes;
    const uint32_t old_version = 31u << 21;  // NanoVDB's own message for it leaked (a fuzz finding)
    std::memcpy(b.data() + 8, &old_version, 4);
    test::write_file(path, b);
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "segment 0: NanoVDB format version 31.0.0, this build reads"});

    b = bytes;
    const uint32_t bad_type = 99;  // the record's grid type: NanoVDB's toStr read past its table (a fuzz finding)
    std::memcpy(b.data() + k_record + 32, &bad_type, 4);
    test::write_file(path, b);
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "grid 'density' is a unknown (99) grid, expected float"});

    b = bytes;
    b[14] = 1;  // the segment's codec: zip
    test::write_file(path, b);
    test::expect_error_message([&] { load_volume_grid(path, {}); }, {path.string(), "compressed"});

    for (size_t n = 1; n < bytes.size(); n += (n < 300 ? 1 : 97)) {
        test::write_file(path, bytes.substr(0, n));
        test::expect_error_message([&] { load_volume_grid(path, {}); }, {path.string()});
    }
}

}  // namespace
}  // namespace npt::media
