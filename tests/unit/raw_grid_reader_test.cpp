// The raw instant-ngp grid reader: axis order, the y flip, the cell-centred local->index map, sRGB decoding
// and bad files, checked through load_volume_grid and sample_trilinear.
#include "media/raw_grid_reader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "core/image_io.h"
#include "log_capture.h"
#include "media/volume_grid.h"
#include "test_support.h"

namespace npt::media {
namespace {

constexpr int W = 4, H = 3, D = 2;

// sigma = i + 10 j + 100 k with j counted from the BOTTOM (local -y); colours distinct per axis.
float sigma_of(int i, int j, int k) { return float(i + 10 * j + 100 * k); }
Vec3 srgb_color_of(int i, int j, int k) { return Vec3(0.1f + 0.2f * i, 0.2f + 0.3f * j, 0.3f + 0.5f * k); }

// Writes the file as instant-ngp does: x fastest, then rows from the TOP (largest y) down, then z.
std::string raw_bytes() {
    std::vector<float> f;
    for (int k = 0; k < D; ++k)
        for (int row = 0; row < H; ++row)
            for (int i = 0; i < W; ++i) {
                const int j = H - 1 - row;
                const Vec3 c = srgb_color_of(i, j, k);
                f.insert(f.end(), {c.x, c.y, c.z, sigma_of(i, j, k)});
            }
    std::string s(f.size() * 4, '\0');
    std::memcpy(s.data(), f.data(), s.size());  // little-endian host, as the format
    return s;
}

GridLoadOptions box_options() {
    GridLoadOptions o;
    o.local_min = Vec3(-1.0f, -2.0f, 0.5f);
    o.local_max = Vec3(1.0f, 2.0f, 4.5f);  // a non-cube box: each axis has its own scale
    return o;
}

// The local point of voxel (i, j, k)'s centre: local_min + (i + 0.5) / W * size.
Vec3 local_centre(const GridLoadOptions& o, int i, int j, int k) {
    const Vec3 size = o.local_max - o.local_min;
    return Vec3(o.local_min.x + (i + 0.5f) / W * size.x, o.local_min.y + (j + 0.5f) / H * size.y,
                o.local_min.z + (k + 0.5f) / D * size.z);
}

TEST(RawGrid, AxisOrderYFlipAndCellCentres) {
    const auto path = test::temp_dir() / "4x3x2_density.bin";
    test::write_file(path, raw_bytes());
    const GridLoadOptions o = box_options();
    const VolumeGrid g = load_volume_grid(path, o);
    // One border voxel on each side repeats the outermost samples (clamp-to-edge inside the cube).
    ASSERT_EQ(g.nx, W + 2);
    ASSERT_EQ(g.ny, H + 2);
    ASSERT_EQ(g.nz, D + 2);
    // Index coordinates of local points carry float rounding of a few ulp of |x| <= 4, i.e. <~ 2e-6 voxels;
    // sigma changes by at most 100 per voxel, so 1e-3 bounds the sigma error with margin.
    for (int k = 0; k < D; ++k)
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
                const FieldSample s =
                    sample_trilinear(g.view(), g.local_to_index.apply(local_centre(o, i, j, k)));
                EXPECT_NEAR(s.density, sigma_of(i, j, k), 1e-3f) << i << " " << j << " " << k;
                const Vec3 c = srgb_color_of(i, j, k);
                test::expect_near(s.color,
                                  Vec3(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z)), 1e-5f);
            }
    // The box's corners are the outer faces of the outer cells: index 0.5 and n + 0.5 (after the border).
    test::expect_near(g.local_to_index.apply(o.local_min), Vec3(0.5f), 1e-5f);
    test::expect_near(g.local_to_index.apply(o.local_max), Vec3(W + 0.5f, H + 0.5f, D + 0.5f), 1e-5f);
    // The y flip, said directly: the file's first value (row 0 = top) is at the largest local y.
    EXPECT_EQ(g.density[g.view().index(1, H, 1)], sigma_of(0, H - 1, 0));
    EXPECT_EQ(g.density[g.view().index(1, 1, 1)], 0.0f);
    // Clamp-to-edge: at the cube's faces the field equals the outermost samples.
    const Vec3 face = g.local_to_index.apply(
        Vec3(o.local_max.x, local_centre(o, W - 1, 1, 1).y, local_centre(o, 0, 1, 1).z));
    EXPECT_NEAR(sample_trilinear(g.view(), face).density, sigma_of(W - 1, 1, 1), 1e-3f);
}

TEST(RawGrid, LinearColoursAreKeptWhenNotSrgb) {
    const auto path = test::temp_dir() / "4x3x2.bin";
    test::write_file(path, raw_bytes());
    GridLoadOptions o = box_options();
    o.raw_color_is_srgb = false;
    const VolumeGrid g = load_volume_grid(path, o);
    EXPECT_EQ(g.color[g.view().index(2, 3, 2)].y, srgb_color_of(1, 2, 1).y);
}

TEST(RawGrid, DimensionsFromTheName) {
    EXPECT_EQ(parse_raw_grid_dims("a/256x128x64_density.bin"), (std::array<size_t, 3>{256, 128, 64}));
    EXPECT_EQ(parse_raw_grid_dims("density_2x3x4.bin"), (std::array<size_t, 3>{2, 3, 4}));
    test::expect_error_message([] { parse_raw_grid_dims("dir/density.bin"); },
                               {"dir/density.bin", "{W}x{H}x{D}"});
    test::expect_error_message([] { parse_raw_grid_dims("4x3_a.bin"); }, {"4x3_a.bin"});
    test::expect_error_message([] { parse_raw_grid_dims("4x3xq_a.bin"); }, {"4x3xq_a.bin"});
    test::expect_error_message([] { parse_raw_grid_dims("99999999999999999999999x1x1_a.bin"); },
                               {"too large"});
}

TEST(RawGrid, WrongFileSizeNamesExpectedAndActual) {
    const auto path = test::temp_dir() / "4x3x2_short.bin";
    std::string bytes = raw_bytes();
    bytes.resize(bytes.size() - 4);
    test::write_file(path, bytes);
    test::expect_error_message([&] { load_volume_grid(path, box_options()); }, {path.string(), "384", "380"});
    test::write_file(path, "");
    test::expect_error_message([&] { load_volume_grid(path, box_options()); }, {path.string(), "384", " 0"});
}

TEST(RawGrid, ZeroAndAbsurdSizesAreRefusedBeforeReading) {
    const auto dir = test::temp_dir();
    test::write_file(dir / "0x3x2_a.bin", "");
    test::expect_error_message([&] { load_volume_grid(dir / "0x3x2_a.bin", {}); }, {"0x3x2_a.bin", "zero"});
    // 1e15 voxels: must be refused from the name alone (the file is empty), not by trying to allocate.
    test::write_file(dir / "100000x100000x100000_a.bin", "");
    test::expect_error_message([&] { load_volume_grid(dir / "100000x100000x100000_a.bin", {}); },
                               {"100000x100000x100000_a.bin", "dense limit"});
    test::write_file(dir / "4x3x2_box.bin", raw_bytes());
    GridLoadOptions empty_box;
    empty_box.local_max = empty_box.local_min;
    test::expect_error_message([&] { load_volume_grid(dir / "4x3x2_box.bin", empty_box); }, {"local box"});
}

TEST(RawGrid, NonFiniteAndNegativeValuesAreZeroedWithOneWarning) {
    const auto path = test::temp_dir() / "2x1x1_bad.bin";
    const float f[8] = {NAN, 0.5f, 0.5f, -3.0f, 0.5f, INFINITY, 0.5f, NAN};
    test::write_file(path, std::string(reinterpret_cast<const char*>(f), sizeof(f)));
    GridLoadOptions o;
    o.raw_color_is_srgb = false;
    test::LogCapture log;
    const VolumeGrid g = load_volume_grid(path, o);
    EXPECT_EQ(log.warnings(), 1) << log.text();
    EXPECT_NE(log.text().find("2 NaN, infinite or negative densities"), std::string::npos) << log.text();
    const GridView v = g.view();  // file voxel i sits at (i + 1, 1, 1) after the clamp-to-edge border
    EXPECT_EQ(g.density[v.index(1, 1, 1)], 0.0f);
    EXPECT_EQ(g.density[v.index(2, 1, 1)], 0.0f);
    test::expect_near(g.color[v.index(1, 1, 1)], Vec3(0.0f, 0.5f, 0.5f), 0.0f);
    test::expect_near(g.color[v.index(2, 1, 1)], Vec3(0.5f, 0.0f, 0.5f), 0.0f);
}

TEST(VolumeGrid, MissingFileAndUnknownExtension) {
    const auto dir = test::temp_dir();
    test::expect_error_message([&] { load_volume_grid(dir / "nope.vdb", {}); }, {"nope.vdb", "not found"});
    test::write_file(dir / "grid.xyz", "data");
    test::expect_error_message([&] { load_volume_grid(dir / "grid.xyz", {}); }, {"grid.xyz", "'.xyz'"});
    test::expect_error_message([&] { load_volume_grid(dir, {}); }, {"not a regular file"});
}

}  // namespace
}  // namespace npt::media
