// nerfpt bake: a hand-built model (random hash grid, so σ and colour vary from voxel to voxel, and an
// occupancy grid with one known occupied box) baked to each format, read back with our readers and compared
// at voxel centres with the per-sample NerfFieldView; sparsity, crops, the fixed-direction colour, placement
// on the cube's local axes, and bad input through the library and the CLI.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "bake/bake_grid.h"
#include "bake/grid_writers.h"
#include "core/image_io.h"
#include "media/volume_grid.h"
#include "nerf/model_file.h"
#include "nerf/object_frame.h"
#include "test_support.h"

namespace npt::bake {
namespace {

namespace fs = std::filesystem;
using nerf::NerfModel;

// The occupied cells of the 16^3 occupancy grid: model x in [4, 8), y in [8, 12), z in [6, 10), i.e. the
// model box [0.25, 0.5) x [0.5, 0.75) x [0.375, 0.625).
constexpr int k_occ_lo[3] = {4, 8, 6}, k_occ_hi[3] = {8, 12, 10};
const nerf::CropBox k_occupied_box{Vec3(0.25f, 0.5f, 0.375f), Vec3(0.5f, 0.75f, 0.625f)};

// The one training camera direction make_model stores (model axes): `avg` bakes the colour seen along it.
const Vec3 k_view_direction = normalize(Vec3(0.3f, -0.5f, 0.8f));

NerfModel make_model() {
    nerf::NerfConfig c;
    c.encoding.grid.levels = 4;
    c.encoding.grid.log2_table_size = 12;
    c.encoding.finest_resolution = 32.0f;
    c.occupancy.resolution = 16;
    NerfModel m = nerf::create_model(c, 1.0f, nerf::ngp_world_to_model(0.33f, Vec3(0.5f)));
    // Hash-grid features of order 1 (not the +-1e-4 of a fresh model), so the field varies in space.
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const nerf::NerfLayout L = m.layout();
    for (size_t i = L.grid_offset; i < L.total; ++i) m.params[i] = u(rng);
    std::vector<float> occ(16 * 16 * 16, 0.0f);
    for (int z = k_occ_lo[2]; z < k_occ_hi[2]; ++z)
        for (int y = k_occ_lo[1]; y < k_occ_hi[1]; ++y)
            for (int x = k_occ_lo[0]; x < k_occ_hi[0]; ++x) occ[size_t(x + 16 * y + 256 * z)] = 1.0f;
    m.occupancy.set_density(occ, c.occupancy.threshold);
    m.view_directions = {k_view_direction};
    return m;
}

// The colour `avg` bakes, from the per-sample query: with one stored view direction, its colour (the
// averaging over several directions and its visibility weights are tested in bake_colour_test.cpp).
Rgb average_color(const nerf::NerfFieldView& view, Vec3 p) {
    float sigma = 0;
    Rgb c;
    view.query(p, k_view_direction, &sigma, &c);
    return c;
}

Rgb srgb_colour_to_linear(Rgb c) { return Rgb(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z)); }

// Tolerances. The bake evaluates the field batched (matrix products, hash encoding in another order) and the
// reference is the per-sample NPT_HD query: they differ by float rounding, ~1e-6 relative on the MLP outputs,
// so σ = exp(raw) agrees to ~1e-6 relative and the sigmoid colours to ~1e-7; srgb_to_linear's slope is at
// most 2.4 / 1.055 ≈ 2.3 on [0, 1], so the linear colours agree to ~3e-7. 1e-4 leaves margin, while a wrong
// voxel, axis or unit is off by O(1).
constexpr float k_sigma_rel = 1e-4f, k_color_abs = 1e-4f;

void write(GridFormat f, const fs::path& path, const BakedGrid& g) {
    switch (f) {
        case GridFormat::vdb:
            write_vdb(path, g);
            break;
        case GridFormat::nvdb:
            write_nvdb(path, g);
            break;
        case GridFormat::raw:
            write_raw(path, g);
            break;
    }
}

// Reads `path` back and checks every baked voxel against the model: density in the file's units and colour in
// linear RGB (the raw reader decodes sRGB), and that nothing else has density.
void expect_round_trip(const NerfModel& model, const BakedGrid& g, GridFormat f, const fs::path& path,
                       std::optional<Vec3> direction = {}) {
    const media::VolumeGrid r = media::load_volume_grid(path, {});
    const nerf::NerfFieldView view = model.field();
    // .vdb/.nvdb: σ per local unit; raw: σ per model unit.
    const float scale = f == GridFormat::raw ? 1.0f : g.layout.model_per_local;
    for (size_t v = 0; v < g.size(); ++v) {
        const int i = g.coords[3 * v], j = g.coords[3 * v + 1], k = g.coords[3 * v + 2];
        const Vec3 x = r.local_to_index.apply(g.layout.local_center(i, j, k));
        const int xi = int(std::lround(x.x)), yi = int(std::lround(x.y)), zi = int(std::lround(x.z));
        ASSERT_NEAR(x.x, xi, 1e-3f);
        ASSERT_NEAR(x.y, yi, 1e-3f);
        ASSERT_NEAR(x.z, zi, 1e-3f);
        const bool inside = xi >= 0 && yi >= 0 && zi >= 0 && xi < r.nx && yi < r.ny && zi < r.nz;
        // The .vdb/.nvdb readers load the density grid's active box: colour-only voxels outside it are not
        // read (they count as 0 there, as any voxel outside the box).
        if (!g.has_density[v] && !inside) continue;
        ASSERT_TRUE(inside) << i << "," << j << "," << k;
        const size_t idx = (size_t(zi) * size_t(r.ny) + size_t(yi)) * size_t(r.nx) + size_t(xi);
        const Vec3 p = g.layout.model_center(i, j, k);
        float sigma = 0;
        Rgb c;
        if (direction) {
            Vec3 d = nerf::world_axes_to_model(*direction);
            view.query(p, d / length(d), &sigma, &c);
        } else {
            sigma = view.density(p);
            c = average_color(view, p);
        }
        if (g.has_density[v])
            EXPECT_NEAR(r.density[idx], sigma * scale, k_sigma_rel * sigma * scale + 1e-6f)
                << i << "," << j << "," << k;
        else
            EXPECT_EQ(r.density[idx], 0.0f);
        test::expect_near(r.color[idx], srgb_colour_to_linear(c), k_color_abs);
    }
    // The raw reader adds a one-voxel clamp-to-edge border (docs/formats.md): count inside it.
    const int b = f == GridFormat::raw ? 1 : 0;
    size_t nonzero = 0;
    for (int z = b; z < r.nz - b; ++z)
        for (int y = b; y < r.ny - b; ++y)
            for (int x = b; x < r.nx - b; ++x)
                nonzero +=
                    r.density[(size_t(z) * size_t(r.ny) + size_t(y)) * size_t(r.nx) + size_t(x)] > 0.0f;
    EXPECT_EQ(nonzero, g.density_voxels);
}

fs::path file_for(GridFormat f, const fs::path& dir, const BakeLayout& L) {
    switch (f) {
        case GridFormat::vdb:
            return dir / "m.vdb";
        case GridFormat::nvdb:
            return dir / "m.nvdb";
        case GridFormat::raw:
            return raw_output_path(dir / "m.bin", L);
    }
    return {};
}

class BakeFormats : public ::testing::TestWithParam<GridFormat> {};

TEST_P(BakeFormats, ReadBackMatchesTheField) {
    const NerfModel model = make_model();
    BakeSettings s;
    s.resolution = 16;
    s.threshold = 0.0f;
    const BakedGrid g = bake_model(model, s);
    ASSERT_GT(g.density_voxels, 0u);
    const fs::path path = file_for(GetParam(), test::temp_dir(), g.layout);
    write(GetParam(), path, g);
    expect_round_trip(model, g, GetParam(), path);
}

// A crop that is not a cube: the grid keeps its proportions in voxels and (nerf_placement.h) fills the cube.
TEST_P(BakeFormats, NonCubicCropAndFixedDirection) {
    const NerfModel model = make_model();
    BakeSettings s;
    s.resolution = 8;
    s.threshold = 0.0f;
    s.crop = nerf::CropBox{Vec3(0.25f, 0.5f, 0.375f), Vec3(0.5f, 0.75f, 0.5f)};
    s.direction = Vec3(0.3f, -0.5f, 2.0f);
    const BakedGrid g = bake_model(model, s);
    // Local x, y, z = model z (0.125), x (0.25), y (0.25).
    EXPECT_EQ(g.layout.dims[0], 4);
    EXPECT_EQ(g.layout.dims[1], 8);
    EXPECT_EQ(g.layout.dims[2], 8);
    EXPECT_EQ(g.density_voxels, 4u * 8u * 8u);  // every voxel lies in the occupied box
    const fs::path path = file_for(GetParam(), test::temp_dir(), g.layout);
    write(GetParam(), path, g);
    expect_round_trip(model, g, GetParam(), path, s.direction);
}

INSTANTIATE_TEST_SUITE_P(, BakeFormats, ::testing::Values(GridFormat::vdb, GridFormat::nvdb, GridFormat::raw),
                         [](const auto& info) {
                             return std::string(info.param == GridFormat::vdb    ? "vdb"
                                                : info.param == GridFormat::nvdb ? "nvdb"
                                                                                 : "raw");
                         });

// Voxel (i, j, k) runs along local x, y, z = model z, x, y, and the default crop (the model's box) fills the
// cube: with 16 voxels, its centre is at model ((j + .5) / 16, (k + .5) / 16, (i + .5) / 16).
TEST(Bake, PlacementFollowsTheCubeAxes) {
    const NerfModel model = make_model();
    BakeSettings s;
    s.resolution = 16;
    const BakeLayout L = make_bake_layout(model, s);
    EXPECT_FLOAT_EQ(L.model_per_local, 0.5f);
    for (int n : {0, 3, 15}) {
        test::expect_near(L.model_center(n, 0, 0), Vec3(0.5f / 16, 0.5f / 16, (n + 0.5f) / 16));
        test::expect_near(L.model_center(0, n, 0), Vec3((n + 0.5f) / 16, 0.5f / 16, 0.5f / 16));
        test::expect_near(L.model_center(0, 0, n), Vec3(0.5f / 16, (n + 0.5f) / 16, 0.5f / 16));
    }
    // The grid's local coordinates invert back through nerf_placement's map.
    const nerf::LocalToModel m = nerf::local_to_model(Vec3(-1.0f), Vec3(1.0f), L.crop);
    test::expect_near(m.inverse_point(L.model_center(2, 5, 11)), L.local_center(2, 5, 11));
}

// Only voxels whose centres lie in occupied cells are evaluated: the 4x4x4 centres of the occupied box, plus
// their colour-only 3x3x3 neighbourhood (6^3 - 4^3), out of 16^3.
TEST(Bake, SparseWhereTheOccupancyGridIsEmpty) {
    const NerfModel model = make_model();
    BakeSettings s;
    s.resolution = 16;
    s.threshold = 0.0f;
    const BakedGrid g = bake_model(model, s);
    EXPECT_EQ(g.density_voxels, 64u);
    EXPECT_EQ(g.size(), 216u);
    const nerf::OccupancyGridView occ = model.occupancy.view();
    for (size_t v = 0; v < g.size(); ++v) {
        const Vec3 p = g.layout.model_center(g.coords[3 * v], g.coords[3 * v + 1], g.coords[3 * v + 2]);
        EXPECT_EQ(g.has_density[v] != 0, occ.is_occupied(p, 0));
    }
    // A threshold drops the thin voxels and only those.
    std::vector<float> sigmas;
    for (size_t v = 0; v < g.size(); ++v)
        if (g.has_density[v]) sigmas.push_back(g.sigma[v]);
    std::sort(sigmas.begin(), sigmas.end());
    s.threshold = 0.5f * (sigmas[31] + sigmas[32]);  // the median, between two voxels
    const BakedGrid thin = bake_model(model, s);
    EXPECT_EQ(thin.density_voxels, 32u);
    for (size_t v = 0; v < thin.size(); ++v)
        if (thin.has_density[v]) {
            EXPECT_GE(thin.sigma[v], *s.threshold);
        }
    EXPECT_GT(default_threshold(model), 0.0f);
}

TEST(Bake, CropIsRespected) {
    const NerfModel model = make_model();
    BakeSettings s;
    s.resolution = 8;
    s.threshold = 0.0f;
    s.crop = k_occupied_box;
    const BakedGrid g = bake_model(model, s);
    EXPECT_EQ(g.density_voxels, 512u);  // all of the crop is occupied
    for (size_t v = 0; v < g.size(); ++v) {
        const Vec3 p = g.layout.model_center(g.coords[3 * v], g.coords[3 * v + 1], g.coords[3 * v + 2]);
        for (int a = 0; a < 3; ++a) {
            EXPECT_GT(p[a], k_occupied_box.min[a]);
            EXPECT_LT(p[a], k_occupied_box.max[a]);
        }
    }
    // --voxel: the same grid by size.
    s.voxel_size = 1.0f / 32.0f;
    EXPECT_EQ(make_bake_layout(model, s).dims[0], 8);
}

TEST(Bake, AnIsolatedModelBakesOnlyItsObjectBox) {
    // An object frame whose object space is model space (object_to_world = the model's world_to_model
    // inverted, a similarity), its box the lower half of the occupied cells: marked object_only (what
    // `nerfpt isolate` does), the bake keeps only the voxels inside the box, as renders cut it; unmarked, the
    // frame alone changes nothing.
    NerfModel model = make_model();
    nerf::ObjectFrame frame;
    frame.object_to_world = model.world_to_model.inverse();
    frame.box_min = k_occupied_box.min;
    frame.box_max = Vec3(k_occupied_box.max.x, k_occupied_box.max.y, 0.5f);
    model.object = frame;
    BakeSettings s;
    s.resolution = 8;
    s.threshold = 0.0f;
    s.crop = k_occupied_box;
    EXPECT_EQ(bake_model(model, s).density_voxels, 512u);
    model.object->object_only = true;
    const BakedGrid g = bake_model(model, s);
    EXPECT_EQ(g.density_voxels, 256u);  // voxel centres at z = 0.39 .. 0.61 in steps of 1/32: four layers of 8
    for (size_t v = 0; v < g.size(); ++v)  // colour-only voxels may border the density ones
        if (g.has_density[v])
            EXPECT_LT(g.layout.model_center(g.coords[3 * v], g.coords[3 * v + 1], g.coords[3 * v + 2]).z, 0.5f);
}

TEST(Bake, DeterministicWhateverTheThreadCount) {
    const NerfModel model = make_model();
    BakeSettings s;
    s.resolution = 24;
    s.threshold = 0.0f;
    const BakedGrid a = bake_model(model, s);
    BakedGrid b;
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        b = bake_model(model, s);
    }
    EXPECT_EQ(a.coords, b.coords);
    EXPECT_EQ(a.sigma, b.sigma);
    ASSERT_EQ(a.color.size(), b.color.size());
    for (size_t v = 0; v < a.size(); ++v) {
        EXPECT_EQ(a.color[v].x, b.color[v].x);
        EXPECT_EQ(a.color[v].y, b.color[v].y);
        EXPECT_EQ(a.color[v].z, b.color[v].z);
    }
}

TEST(Bake, BadSettingsAreOneLineErrors) {
    const NerfModel model = make_model();
    BakeSettings s;
    s.resolution = 0;
    test::expect_error_message([&] { make_bake_layout(model, s); }, {"--res 0"});
    s.resolution = 16;
    s.crop = nerf::CropBox{Vec3(0.5f, 0.2f, 0.2f), Vec3(0.4f, 0.8f, 0.8f)};
    test::expect_error_message([&] { make_bake_layout(model, s); }, {"--crop", "minimum", "x: 0.5 >= 0.4"});
    s.crop = nerf::CropBox{Vec3(-0.5f, 0.2f, 0.2f), Vec3(0.4f, 0.8f, 0.8f)};
    test::expect_error_message([&] { make_bake_layout(model, s); }, {"--crop", "inside the model's box"});
    s.crop.reset();
    s.resolution = 4000;
    test::expect_error_message([&] { make_bake_layout(model, s); }, {"--res 4000", "voxels"});
    s.resolution = 1024;
    test::expect_error_message([&] { check_raw_size(make_bake_layout(model, s)); }, {"--res", "raw"});
    s.resolution = 8;
    s.direction = Vec3(0.0f);
    test::expect_error_message([&] { bake_model(model, s); }, {"--direction"});
    test::expect_error_message([] { grid_format_from_name("exr"); }, {"--format 'exr'", "unknown"});
    test::expect_error_message([] { grid_format_from_path("a.exr"); }, {"--output 'a.exr'", ".vdb"});
    test::expect_error_message([] { check_extension("a.vdb", GridFormat::nvdb); }, {"'a.vdb'", ".nvdb"});
    BakeLayout L;
    L.dims[0] = 4, L.dims[1] = 5, L.dims[2] = 6;
    EXPECT_EQ(raw_output_path("d/lego.bin", L), fs::path("d/4x5x6_lego.bin"));
    EXPECT_EQ(raw_output_path("d/4x5x6_lego.bin", L), fs::path("d/4x5x6_lego.bin"));
    test::expect_error_message([&] { raw_output_path("d/8x8x8_lego.bin", L); }, {"8x8x8_lego.bin", "4x5x6"});
}

// A folder we cannot write into (its "folder" is a file): one line naming the file, and nothing left behind.
TEST(Bake, UnwritableOutputLeavesNothing) {
    const NerfModel model = make_model();
    BakeSettings s;
    s.resolution = 8;
    const BakedGrid g = bake_model(model, s);
    const fs::path dir = test::temp_dir();
    test::write_file(dir / "file", "x");
    for (GridFormat f : {GridFormat::vdb, GridFormat::nvdb, GridFormat::raw}) {
        const fs::path bad = file_for(f, dir / "file", g.layout);
        test::expect_error_message([&] { write(f, bad, g); }, {bad.string()});
    }
    size_t entries = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
    EXPECT_EQ(entries, 1u);
}

// --- the command line -------------------------------------------------------------------------------------

using test::run_cli;
fs::path cli() { return test::cli_binary(); }
std::string slurp(const fs::path& p) { return test::read_text(p); }

TEST(BakeCli, BakesAndRefusesBadInput) {
    if (!fs::exists(cli())) GTEST_SKIP() << "nerfpt binary not built: " << cli();
    const fs::path dir = test::temp_dir();
    nerf::save_model(dir / "m.npt", make_model(), false);
    const std::string m = (dir / "m.npt").string(), log = (dir / "log").string();

    ASSERT_EQ(run_cli({"bake", m, "-o", (dir / "out" / "m.vdb").string(), "--res", "16", "-q"}, log), 1);
    ASSERT_EQ(
        run_cli({"bake", m, "-o", (dir / "m.vdb").string(), "--res", "16", "--threshold", "0", "-q"}, log), 0)
        << slurp(log);
    EXPECT_NE(slurp(log).find("64 with density"), std::string::npos) << slurp(log);
    ASSERT_EQ(run_cli({"bake", m, "-o", (dir / "m.bin").string(), "--res", "16", "-q"}, log), 0)
        << slurp(log);
    EXPECT_TRUE(fs::exists(dir / "16x16x16_m.bin"));

    struct Bad {
        std::vector<std::string> args;
        int code;
        std::string says;
    };
    const std::vector<Bad> bad = {
        {{"bake", (dir / "none.npt").string(), "-o", (dir / "x.vdb").string()}, 1, "none.npt"},
        {{"bake", m, "-o", (dir / "x.vdb").string(), "--res", "0"}, 2, "--res"},
        {{"bake", m, "-o", (dir / "x.vdb").string(), "--crop", "0.6,0,0,0.5,1,1"}, 1, "--crop"},
        {{"bake", m, "-o", (dir / "x.vdb").string(), "--crop", "0,0,0,1,1"}, 1, "--crop"},
        {{"bake", m, "-o", (dir / "x.exr").string()}, 1, "--output"},
        {{"bake", m, "-o", (dir / "x.vdb").string(), "--format", "exr"}, 1, "--format"},
        {{"bake", m, "-o", (dir / "no" / "x.vdb").string()}, 1, "--output"},
        {{"bake", m, "-o", (dir / "x.vdb").string(), "--direction", "1,2"}, 1, "--direction"},
    };
    for (const auto& b : bad) {
        EXPECT_EQ(run_cli(b.args, log), b.code) << slurp(log);
        const std::string text = slurp(log);
        EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
        EXPECT_NE(text.find(b.says), std::string::npos) << text;
    }
    // Only the two good outputs and what the test wrote: no partial or temporary files.
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    EXPECT_EQ(names, (std::vector<std::string>{"16x16x16_m.bin", "log", "m.npt", "m.vdb"}));
}

}  // namespace
}  // namespace npt::bake
