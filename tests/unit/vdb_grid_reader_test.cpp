// OpenVDB (.vdb) and NanoVDB (.nvdb) grid readers: grids built here with known voxels and transforms (voxel
// size 0.1 + translation, and a rotation), written, loaded and sampled at local points against hand-computed
// values; bad files; and cornell_volume's real volume.vdb.
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <numbers>
#include <string>
#include <vector>

#include "bake/nanovdb_convert.h"
#include "log_capture.h"
#include "media/volume_grid.h"
#include "test_support.h"

namespace npt::media {
namespace {

namespace fs = std::filesystem;
using openvdb::Coord;
using openvdb::Vec3d;
using openvdb::Vec3s;

enum class Format { openvdb, nanovdb };
void PrintTo(Format f, std::ostream* os) { *os << (f == Format::openvdb ? "OpenVDB" : "NanoVDB"); }

void write_grids(const fs::path& path, const openvdb::GridPtrVec& grids, Format format) {
    if (format == Format::openvdb) {
        openvdb::io::File(path.string()).write(grids);
        return;
    }
    bake::write_nanovdb_grids(path, grids, /*full_checksum=*/true);
}

// Voxel size 0.1, translation (0.3, -0.2, 0.5): index (i, j, k) is at local 0.1 (i, j, k) + (0.3, -0.2, 0.5).
openvdb::math::Transform::Ptr scaled_translated() {
    auto xf = openvdb::math::Transform::createLinearTransform(0.1);
    xf->postTranslate(Vec3d(0.3, -0.2, 0.5));
    return xf;
}

// Scale 0.1, then 90 degrees about +z ((x, y, z) -> (-y, x, z)), then translation (1, 2, 3).
openvdb::math::Transform::Ptr rotated() {
    auto xf = openvdb::math::Transform::createLinearTransform(0.1);
    xf->postRotate(std::numbers::pi / 2, openvdb::math::Z_AXIS);
    xf->postTranslate(Vec3d(1.0, 2.0, 3.0));
    return xf;
}

// Four voxels, one at negative indices so that the dense box does not start at 0.
openvdb::GridPtrVec known_grids(const openvdb::math::Transform::Ptr& xf) {
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->setTransform(xf);
    auto color = openvdb::Vec3SGrid::create(Vec3s(0.0f));
    color->setName("color");
    color->setTransform(xf->copy());
    auto d = density->getAccessor();
    auto c = color->getAccessor();
    d.setValue(Coord(2, 3, 4), 0.5f);
    c.setValue(Coord(2, 3, 4), Vec3s(1, 0, 0));
    d.setValue(Coord(3, 3, 4), 1.0f);
    c.setValue(Coord(3, 3, 4), Vec3s(0, 1, 0));
    d.setValue(Coord(2, 4, 4), 0.25f);
    c.setValue(Coord(2, 4, 4), Vec3s(0, 0, 1));
    d.setValue(Coord(-1, 0, 2), 0.75f);
    c.setValue(Coord(-1, 0, 2), Vec3s(1, 1, 1));
    return {density, color};
}

FieldSample sample_local(const VolumeGrid& g, Vec3 p) {
    return sample_trilinear(g.view(), g.local_to_index.apply(p));
}

// Local points carry float rounding of ~1e-7 relative through the affine map: index errors of ~1e-5 voxels at
// most here, and the values change by at most 1 per voxel, so 1e-5 is the tolerance.
constexpr float k_tol = 1e-5f;

class VdbGrid : public ::testing::TestWithParam<Format> {
  protected:
    static void SetUpTestSuite() { openvdb::initialize(); }
    fs::path file(const std::string& stem) const {
        return test::temp_dir() / (stem + (GetParam() == Format::openvdb ? ".vdb" : ".nvdb"));
    }
};

TEST_P(VdbGrid, ScaledTranslatedGridSampledAtLocalPoints) {
    const auto path = file("known");
    write_grids(path, known_grids(scaled_translated()), GetParam());
    test::LogCapture log;
    const VolumeGrid g = load_volume_grid(path, {});
    EXPECT_EQ(log.warnings(), 0) << log.text();
    // Active bbox [-1, 3] x [0, 4] x [2, 4].
    EXPECT_EQ(g.nx, 5);
    EXPECT_EQ(g.ny, 5);
    EXPECT_EQ(g.nz, 3);
    // Voxel (2, 3, 4) at local (0.5, 0.1, 0.9).
    auto s = sample_local(g, Vec3(0.5f, 0.1f, 0.9f));
    EXPECT_NEAR(s.density, 0.5f, k_tol);
    test::expect_near(s.color, Vec3(1, 0, 0), k_tol);
    // Index (2.5, 3, 4): half way to (3, 3, 4).
    s = sample_local(g, Vec3(0.55f, 0.1f, 0.9f));
    EXPECT_NEAR(s.density, 0.75f, k_tol);
    test::expect_near(s.color, Vec3(0.5f, 0.5f, 0), k_tol);
    // Index (2.5, 3.5, 4): a quarter each of (2,3,4), (3,3,4), (2,4,4) and the inactive (3,4,4).
    s = sample_local(g, Vec3(0.55f, 0.15f, 0.9f));
    EXPECT_NEAR(s.density, 0.25f * (0.5f + 1.0f + 0.25f), k_tol);
    test::expect_near(s.color, Vec3(0.25f), k_tol);
    // Index (2, 3, 4.5): half of (2,3,4), the other half outside the dense box (0).
    EXPECT_NEAR(sample_local(g, Vec3(0.5f, 0.1f, 0.95f)).density, 0.25f, k_tol);
    // The negative-index voxel (-1, 0, 2) at local (0.2, -0.2, 0.7).
    EXPECT_NEAR(sample_local(g, Vec3(0.2f, -0.2f, 0.7f)).density, 0.75f, k_tol);
    EXPECT_EQ(sample_local(g, Vec3(0.0f)).density, 0.0f);
}

TEST_P(VdbGrid, RotatedGridSampledAtLocalPoints) {
    const auto xf = rotated();
    // The hand computation below, checked against OpenVDB's own map once.
    const Vec3d w = xf->indexToWorld(Coord(2, 3, 4));
    ASSERT_NEAR(w.x(), 0.7, 1e-12);
    ASSERT_NEAR(w.y(), 2.2, 1e-12);
    ASSERT_NEAR(w.z(), 3.4, 1e-12);
    const auto path = file("rotated");
    write_grids(path, known_grids(xf), GetParam());
    const VolumeGrid g = load_volume_grid(path, {});
    // Voxel (2, 3, 4): scaled (0.2, 0.3, 0.4), rotated (-0.3, 0.2, 0.4), translated (0.7, 2.2, 3.4).
    auto s = sample_local(g, Vec3(0.7f, 2.2f, 3.4f));
    EXPECT_NEAR(s.density, 0.5f, k_tol);
    test::expect_near(s.color, Vec3(1, 0, 0), k_tol);
    // Index (2.5, 3, 4): scaled (0.25, 0.3, 0.4), rotated (-0.3, 0.25, 0.4), translated (0.7, 2.25, 3.4).
    s = sample_local(g, Vec3(0.7f, 2.25f, 3.4f));
    EXPECT_NEAR(s.density, 0.75f, k_tol);
    test::expect_near(s.color, Vec3(0.5f, 0.5f, 0), k_tol);
    // Index (2, 3.5, 4): rotated (-0.35, 0.2, 0.4) -> (0.65, 2.2, 3.4): half of (2,3,4) and of (2,4,4).
    EXPECT_NEAR(sample_local(g, Vec3(0.65f, 2.2f, 3.4f)).density, 0.375f, k_tol);
}

TEST_P(VdbGrid, ColourOnOtherVoxelsIsResampledAtDensityVoxels) {
    auto grids = known_grids(scaled_translated());
    // Colour on a grid of half the voxel size, holding a linear function of the local point f(p) = (x, y + 1,
    // z) over a box that covers the density's: trilinear resampling reproduces a linear function exactly.
    auto color = openvdb::Vec3SGrid::create(Vec3s(0.0f));
    color->setName("color");
    auto cxf = openvdb::math::Transform::createLinearTransform(0.05);
    cxf->postTranslate(Vec3d(0.3, -0.2, 0.5));
    color->setTransform(cxf);
    auto acc = color->getAccessor();
    for (int k = 0; k <= 12; ++k)
        for (int j = -4; j <= 12; ++j)
            for (int i = -6; i <= 10; ++i) {
                const Vec3d p = cxf->indexToWorld(Coord(i, j, k));
                acc.setValue(Coord(i, j, k), Vec3s(float(p.x()), float(p.y() + 1.0), float(p.z())));
            }
    grids[1] = color;
    const auto path = file("resampled");
    write_grids(path, grids, GetParam());
    const VolumeGrid g = load_volume_grid(path, {});
    // At density voxels (2,3,4) and (-1,0,2).
    test::expect_near(sample_local(g, Vec3(0.5f, 0.1f, 0.9f)).color, Vec3(0.5f, 1.1f, 0.9f), k_tol);
    test::expect_near(sample_local(g, Vec3(0.2f, -0.2f, 0.7f)).color, Vec3(0.2f, 0.8f, 0.7f), k_tol);
}

TEST_P(VdbGrid, ActiveTilesAreExpanded) {
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->tree().addTile(1, Coord(0, 0, 0), 0.5f, true);  // one active level-1 tile: 8^3 voxels
    const auto path = file("tile");
    write_grids(path, {density}, GetParam());
    test::LogCapture log;
    const VolumeGrid g = load_volume_grid(path, {});
    EXPECT_EQ(log.warnings(), 1) << log.text();  // no colour grid: white, said once
    ASSERT_EQ(g.nx, 8);
    ASSERT_EQ(g.ny, 8);
    ASSERT_EQ(g.nz, 8);
    for (float v : g.density) ASSERT_EQ(v, 0.5f);
    for (Vec3 c : g.color) ASSERT_EQ(c.x + c.y + c.z, 3.0f);
}

TEST_P(VdbGrid, NegativeNaNAndInfDensitiesAreZeroedWithOneWarning) {
    auto grids = known_grids(scaled_translated());
    auto d = openvdb::gridPtrCast<openvdb::FloatGrid>(grids[0])->getAccessor();
    d.setValue(Coord(2, 3, 4), -1.0f);
    d.setValue(Coord(3, 3, 4), std::nanf(""));
    d.setValue(Coord(2, 4, 4), INFINITY);
    const auto path = file("bad_values");
    write_grids(path, grids, GetParam());
    test::LogCapture log;
    const VolumeGrid g = load_volume_grid(path, {});
    EXPECT_EQ(log.warnings(), 1) << log.text();
    EXPECT_NE(log.text().find("3 NaN, infinite or negative densities"), std::string::npos) << log.text();
    for (float v : g.density) EXPECT_TRUE(v == 0.0f || v == 0.75f);
}

TEST_P(VdbGrid, MissingDensityListsTheGrids) {
    auto grids = known_grids(scaled_translated());
    grids[0]->setName("foo");
    const auto path = file("no_density");
    write_grids(path, grids, GetParam());
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "no grid 'density'", "'foo'", "'color'"});
}

TEST_P(VdbGrid, WrongGridTypes) {
    auto grids = known_grids(scaled_translated());
    grids[0]->setName("color");
    grids[1]->setName("density");  // a Vec3 grid named density
    const auto path = file("swapped");
    write_grids(path, grids, GetParam());
    test::expect_error_message([&] { load_volume_grid(path, {}); }, {path.string(), "'density'", "vec3"});

    grids[0]->setName("density");
    auto float_color = openvdb::FloatGrid::create(0.0f);
    float_color->setName("color");
    float_color->tree().setValue(Coord(0), 1.0f);
    grids[1] = float_color;
    const auto path2 = file("float_color");
    write_grids(path2, grids, GetParam());
    test::expect_error_message([&] { load_volume_grid(path2, {}); }, {path2.string(), "'color'", "float"});
}

TEST_P(VdbGrid, NonZeroBackgroundEmptyGridAndOversizedGrid) {
    auto density = openvdb::FloatGrid::create(1.0f);
    density->setName("density");
    density->tree().setValue(Coord(0), 2.0f);
    auto path = file("background");
    write_grids(path, {density}, GetParam());
    test::expect_error_message([&] { load_volume_grid(path, {}); }, {path.string(), "non-zero background"});

    density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    path = file("empty");
    write_grids(path, {density}, GetParam());
    test::expect_error_message([&] { load_volume_grid(path, {}); }, {path.string(), "no active voxels"});

    // 1024^3 voxels as a few active tiles: cheap to store, refused before the dense array is allocated.
    density->fill(openvdb::CoordBBox(Coord(0), Coord(1023)), 0.5f, true);
    path = file("huge");
    write_grids(path, {density}, GetParam());
    test::expect_error_message([&] { load_volume_grid(path, {}); },
                               {path.string(), "1024x1024x1024", "dense limit"});
}

TEST_P(VdbGrid, NotAGridFile) {
    const auto path = file("garbage");
    test::write_file(path, "this is not a grid file, not even close");
    test::expect_error_message([&] { load_volume_grid(path, {}); }, {path.string(), "cannot read"});
    test::write_file(path, "");
    test::expect_error_message([&] { load_volume_grid(path, {}); }, {path.string()});

    // A real file cut at several points.
    const auto whole = file("whole");
    write_grids(whole, known_grids(scaled_translated()), GetParam());
    std::ifstream in(whole, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (double fraction : {0.1, 0.5, 0.9, 0.99}) {
        const auto cut = file("truncated");
        test::write_file(cut, bytes.substr(0, size_t(double(bytes.size()) * fraction)));
        test::expect_error_message([&] { load_volume_grid(cut, {}); }, {cut.string()});
    }
}

// OpenVDB 10 trusts the size fields inside a grid (bloscFromStream, zipFromStream): a flipped one made it ask
// for 2^60 bytes, or copy a block of the claimed size past the end of a node's buffer. Each 8 bytes of the
// file that read as a plausible size (a compressed block's, or minus an uncompressed one's) is set to 2^60 +
// 64, then to the size plus 64: every load ends in an npt::Error naming the file (no other exception, no
// sanitizer report) or loads, and the blocks' sizes are among the errors.
TEST(OpenVdbCorruptSize, SizeFieldsAreCheckedBeforeOpenVdbTrustsThem) {
    openvdb::initialize();
    const uint32_t compressions[] = {openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK,
                                     openvdb::io::COMPRESS_ZIP, openvdb::io::COMPRESS_NONE};
    for (const uint32_t compression : compressions) {
        const auto path = test::temp_dir() / "sizes.vdb";
        openvdb::io::File file(path.string());
        file.setCompression(compression);
        file.write(known_grids(scaled_translated()));
        std::ifstream in(path, std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        int tried = 0, block_errors = 0;
        for (size_t at = 0; at + 8 <= bytes.size(); ++at) {
            int64_t v;
            std::memcpy(&v, bytes.data() + at, 8);
            if (v == 0 || v < -int64_t(bytes.size()) || v > int64_t(bytes.size())) continue;
            for (const int64_t bad_value : {(int64_t(1) << 60) + 64, v < 0 ? v - 64 : v + 64}) {
                std::string bad = bytes;
                std::memcpy(bad.data() + at, &bad_value, 8);
                test::write_file(path, bad);
                ++tried;
                try {
                    load_volume_grid(path, {});
                } catch (const Error& e) {
                    const std::string msg = e.what();
                    EXPECT_NE(msg.find(path.string()), std::string::npos) << msg;
                    block_errors += msg.find("block") != std::string::npos;
                }
            }
        }
        EXPECT_GT(tried, 0);
        EXPECT_GT(block_errors, 0) << "compression " << compression << ": no block size among " << tried;
    }
}

// NanoVDB files carry a CRC checksum; nerfpt bake writes a full one (voxel data included) and the reader
// verifies it, so a flipped voxel is an error. NanoVDB's default partial checksum leaves voxels uncovered:
// such a file loads with a warning that says so.
TEST(NanoVdbChecksum, AFlippedVoxelValueIsDetected) {
    openvdb::initialize();
    const auto flip_last_075 = [](const fs::path& path) {
        std::ifstream in(path, std::ios::binary);
        std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        const std::string pattern("\0\0\x40\x3f", 4);  // 0.75f, the voxel at (-1, 0, 2), in its leaf
        const size_t at = bytes.rfind(pattern);
        ASSERT_NE(at, std::string::npos);
        bytes[at + 2] = char(bytes[at + 2] ^ 0x01);
        test::write_file(path, bytes);
    };
    const auto full = test::temp_dir() / "full.nvdb";
    write_grids(full, known_grids(scaled_translated()), Format::nanovdb);
    EXPECT_NO_THROW(load_volume_grid(full, {}));
    flip_last_075(full);
    test::expect_error_message([&] { load_volume_grid(full, {}); }, {full.string(), "'density'", "corrupt"});

    const auto partial = test::temp_dir() / "partial.nvdb";
    bake::write_nanovdb_grids(partial, known_grids(scaled_translated()), /*full_checksum=*/false);
    flip_last_075(partial);
    test::LogCapture log;
    EXPECT_NO_THROW(load_volume_grid(partial, {}));
    EXPECT_NE(log.text().find("only a partial checksum"), std::string::npos) << log.text();
}

INSTANTIATE_TEST_SUITE_P(Formats, VdbGrid, ::testing::Values(Format::openvdb, Format::nanovdb),
                         [](const auto& info) {
                             return info.param == Format::openvdb ? "OpenVdb" : "NanoVdb";
                         });

// cornell_volume's volume.vdb (see its README): 64^3 voxels of size 2/64 over the cube [-1, 1]^3, voxel (i,
// j, k) at local -1 + (i + 1/2) 2/64.
TEST(CornellVolumeVdb, VoxelCentreSampleEqualsTheStoredVoxel) {
    const auto path = test::shared_data() / "scenes" / "cornell_volume" / "volume.vdb";
    NPT_REQUIRE_SHARED(path);
    openvdb::initialize();
    openvdb::io::File file(path.string());
    file.open(false);
    auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid("density"));
    auto color = openvdb::gridPtrCast<openvdb::Vec3SGrid>(file.readGrid("color"));
    ASSERT_TRUE(density && color);
    const openvdb::CoordBBox bbox = density->evalActiveVoxelBoundingBox();

    const VolumeGrid g = load_volume_grid(path, {});
    // The file's index space is [0, 63]^3 but only voxels with density > 0 are stored (active): the dense
    // grid covers their bounding box ((2, 3, 2) + 59x52x52 in the current file), and local_to_index shifts by
    // its min.
    EXPECT_EQ(g.nx, bbox.dim().x());
    EXPECT_EQ(g.ny, bbox.dim().y());
    EXPECT_EQ(g.nz, bbox.dim().z());
    EXPECT_TRUE(openvdb::CoordBBox(Coord(0), Coord(63)).isInside(bbox));
    EXPECT_TRUE(color->transform() == density->transform());
    // Voxel size 2/64: 32 voxels per local unit, no rotation; voxel 0's and 63's centres at the README's
    // local points -1 + (i + 1/2) 2/64.
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(g.local_to_index.m[3 * r + c], r == c ? 32.0f : 0.0f, 1e-4f);
    const Vec3 lo(float(bbox.min().x()), float(bbox.min().y()), float(bbox.min().z()));
    test::expect_near(g.local_to_index.apply(Vec3(-1.0f + 1.0f / 64.0f)), -lo, 1e-5f);
    test::expect_near(g.local_to_index.apply(Vec3(1.0f - 1.0f / 64.0f)), Vec3(63.0f) - lo, 1e-5f);

    const float p = -1.0f + 32.5f * 2.0f / 64.0f;  // exact in float
    const FieldSample s = sample_local(g, Vec3(p));
    const float expected = density->tree().getValue(Coord(32));
    const Vec3s c = color->tree().getValue(Coord(32));
    EXPECT_GT(expected, 0.0f);
    EXPECT_NEAR(s.density, expected, 1e-6f);
    test::expect_near(s.color, Vec3(c[0], c[1], c[2]), 1e-6f);
}

}  // namespace
}  // namespace npt::media
