// A sequence frame's EXR: the header attributes written (fps, worldToCamera, nerfpt.*) read back, and the
// "reads back whole" check that lets a shot skip finished frames: true for a whole file, false for a missing,
// truncated or differently sized one.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/image_io.h"
#include "test_support.h"

namespace npt {
namespace {

namespace fs = std::filesystem;

Image ramp(int w, int h) {
    Image im(w, h, 3);
    for (size_t i = 0; i < im.pixels.size(); ++i) im.pixels[i] = float(i) * 0.01f;
    return im;
}

TEST(ExrMetadata, RoundTrips) {
    const fs::path p = test::temp_dir() / "meta.exr";
    ExrMetadata m;
    m.fps = 24.0;
    m.has_camera = true;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m.world_to_camera[r][c] = float(r * 4 + c);
    m.ints.push_back({"nerfpt.frame", 17});
    m.floats.push_back({"nerfpt.time", 0.708f});
    m.strings.push_back({"nerfpt.seed", "12345678901234567890"});
    write_exr_layers(p, ramp(8, 4), {}, &m);
    const ExrMetadata back = read_exr_metadata(p);
    EXPECT_DOUBLE_EQ(back.fps, 24.0);
    ASSERT_TRUE(back.has_camera);
    EXPECT_EQ(back.world_to_camera[3][1], 13.0f);
    EXPECT_EQ(back.world_to_camera[1][3], 7.0f);
    const auto has_int = [&](const std::string& n, int v) {
        for (const auto& [name, value] : back.ints)
            if (name == n) return value == v;
        return false;
    };
    EXPECT_TRUE(has_int("nerfpt.frame", 17));
    bool seed = false;
    for (const auto& [name, value] : back.strings) seed |= name == "nerfpt.seed" && value == "12345678901234567890";
    EXPECT_TRUE(seed);
    m.fps = 29.97;  // NTSC: written as 30000/1001
    write_exr_layers(p, ramp(8, 4), {}, &m);
    EXPECT_NEAR(read_exr_metadata(p).fps, 30000.0 / 1001.0, 1e-9);
}

TEST(ExrMetadata, ReadsBackWholeOnlyWhenWhole) {
    const fs::path p = test::temp_dir() / "whole.exr";
    write_exr_layers(p, ramp(64, 48), {});
    EXPECT_TRUE(exr_reads_back_whole(p, 64, 48));
    EXPECT_FALSE(exr_reads_back_whole(p, 48, 64));  // another --res: rendered again
    EXPECT_FALSE(exr_reads_back_whole(test::temp_dir() / "missing.exr", 64, 48));
    const std::string bytes = test::read_text(p);
    const fs::path cut = test::temp_dir() / "cut.exr";
    for (size_t keep : {size_t(0), size_t(100), bytes.size() / 2, bytes.size() - 1}) {
        test::write_file(cut, bytes.substr(0, keep));
        EXPECT_FALSE(exr_reads_back_whole(cut, 64, 48)) << keep << " of " << bytes.size() << " bytes";
    }
}

}  // namespace
}  // namespace npt
