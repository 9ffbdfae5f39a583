// nerfpt bake --colour albedo: a relightable model made in code (random hash grids for σ and for the intrinsic
// field, one occupied box) baked with its albedo; every baked voxel's colour must be the intrinsic field's
// albedo at the voxel's centre, in the BakedGrid and read back from the .vdb, the density voxels those of the
// radiance bake; bad input (albedo of a model without a relight section, albedo with --direction) through the
// library and the CLI.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "bake/bake_grid.h"
#include "bake/grid_writers.h"
#include "core/error.h"
#include "core/srgb.h"
#include "media/volume_grid.h"
#include "nerf/model_file.h"
#include "test_support.h"

namespace npt::bake {
namespace {

namespace fs = std::filesystem;
using nerf::NerfModel;

NerfModel make_model(bool relightable) {
    nerf::NerfConfig c;
    c.encoding.grid.levels = 4;
    c.encoding.grid.log2_table_size = 12;
    c.encoding.finest_resolution = 32.0f;
    c.occupancy.resolution = 16;
    NerfModel m = nerf::create_model(c, 1.0f, nerf::ngp_world_to_model(0.33f, Vec3(0.5f)));
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const nerf::NerfLayout L = m.layout();
    for (size_t i = L.grid_offset; i < L.total; ++i) m.params[i] = u(rng);
    // Occupied: model [0.25, 0.5) x [0.5, 0.75) x [0.375, 0.625).
    std::vector<float> occ(16 * 16 * 16, 0.0f);
    for (int z = 6; z < 10; ++z)
        for (int y = 8; y < 12; ++y)
            for (int x = 4; x < 8; ++x) occ[size_t(x + 16 * y + 256 * z)] = 1.0f;
    m.occupancy.set_density(occ, c.occupancy.threshold);
    m.view_directions = {normalize(Vec3(0.3f, -0.5f, 0.8f))};
    if (relightable) {
        nerf::RelightFields f;
        f.config.grid = {4, 2, 10, 4, 1.5f};
        f.config.finest_resolution = 64.0f;
        f.config.width = 16;
        f.config.hidden_layers = 1;
        // Weights of order 1: the albedo then varies over the box (a constant one would not tell voxels apart).
        f.params.resize(nerf::make_intrinsic_layout(f.config, m.aabb_scale).total);
        for (float& p : f.params) p = u(rng);
        f.capture_env.width = 2;
        f.capture_env.height = 1;
        f.capture_env.texels = {Rgb(1.0f), Rgb(1.0f)};
        f.exposure = {Rgb(1.0f)};
        m.relight = f;
    }
    return m;
}

Rgb to_linear(Rgb c) { return Rgb(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z)); }

// The baked albedo goes through linear_to_srgb and back (BakedGrid keeps sRGB-encoded colours): float rounding
// of pow, ~1e-6 relative; the bake and the reference use the same per-point query. A wrong voxel or a radiance
// colour is off by O(0.1).
constexpr float k_albedo_abs = 1e-5f;

BakeSettings albedo_settings() {
    BakeSettings s;
    s.resolution = 16;
    s.threshold = 0.0f;
    s.colour = BakeColour::albedo;
    return s;
}

TEST(BakeAlbedo, ColourIsTheIntrinsicAlbedoAtVoxelCentres) {
    const NerfModel model = make_model(true);
    const BakedGrid g = bake_model(model, albedo_settings());
    EXPECT_EQ(g.colour, BakeColour::albedo);
    ASSERT_EQ(g.density_voxels, 64u);  // the occupied box, 4 x 4 x 4 voxels of 1/16
    const nerf::IntrinsicFieldView intrinsic = model.intrinsic();
    float lo = 1.0f, hi = 0.0f;
    for (size_t v = 0; v < g.size(); ++v) {
        const Vec3 p = g.layout.model_center(g.coords[3 * v], g.coords[3 * v + 1], g.coords[3 * v + 2]);
        const Rgb want = intrinsic.query(p).albedo;
        test::expect_near(to_linear(g.color[v]), want, k_albedo_abs);
        lo = std::min(lo, want.x);
        hi = std::max(hi, want.x);
    }
    EXPECT_GT(hi - lo, 0.05f) << "the albedo must vary for the test to tell voxels apart";

    // The same voxels and σ as the radiance bake: only the colour differs.
    BakeSettings rs = albedo_settings();
    rs.colour = BakeColour::radiance;
    const BakedGrid r = bake_model(model, rs);
    EXPECT_EQ(r.coords, g.coords);
    EXPECT_EQ(r.sigma, g.sigma);
    size_t differ = 0;
    for (size_t v = 0; v < g.size(); ++v) differ += std::abs(r.color[v].x - g.color[v].x) > 1e-3f;
    EXPECT_GT(differ, g.size() / 2);
}

TEST(BakeAlbedo, VdbHoldsTheLinearAlbedo) {
    const NerfModel model = make_model(true);
    const BakedGrid g = bake_model(model, albedo_settings());
    const fs::path path = test::temp_dir() / "albedo.vdb";
    write_vdb(path, g);
    const media::VolumeGrid r = media::load_volume_grid(path, {});
    const nerf::IntrinsicFieldView intrinsic = model.intrinsic();
    size_t checked = 0;
    for (size_t v = 0; v < g.size(); ++v) {
        if (!g.has_density[v]) continue;  // the reader loads the density grid's active box
        const int i = g.coords[3 * v], j = g.coords[3 * v + 1], k = g.coords[3 * v + 2];
        const Vec3 x = r.local_to_index.apply(g.layout.local_center(i, j, k));
        const int xi = int(std::lround(x.x)), yi = int(std::lround(x.y)), zi = int(std::lround(x.z));
        ASSERT_TRUE(xi >= 0 && yi >= 0 && zi >= 0 && xi < r.nx && yi < r.ny && zi < r.nz);
        const size_t idx = (size_t(zi) * size_t(r.ny) + size_t(yi)) * size_t(r.nx) + size_t(xi);
        test::expect_near(r.color[idx], intrinsic.query(g.layout.model_center(i, j, k)).albedo, k_albedo_abs);
        ++checked;
    }
    EXPECT_EQ(checked, 64u);
}

TEST(BakeAlbedo, BadSettingsAreOneLineErrors) {
    auto message = [](const NerfModel& m, const BakeSettings& s) -> std::string {
        try {
            check_colour_settings(m, s, "m.npt");
            bake_model(m, s);
        } catch (const Error& e) {
            return e.what();
        }
        return "";
    };
    const std::string plain = message(make_model(false), albedo_settings());
    EXPECT_NE(plain.find("m.npt: --colour albedo needs a relightable model"), std::string::npos) << plain;
    EXPECT_EQ(plain.find('\n'), std::string::npos);
    BakeSettings s = albedo_settings();
    s.direction = Vec3(0.0f, 0.0f, 1.0f);
    const std::string dir = message(make_model(true), s);
    EXPECT_EQ(dir.rfind("--direction 0,0,1:", 0), 0u) << dir;
    // The library refuses without the CLI's check too.
    EXPECT_THROW(bake_model(make_model(false), albedo_settings()), Error);
}

TEST(BakeAlbedoCli, BakesAndRefusesBadInput) {
    const fs::path cli = test::cli_binary();
    if (!fs::exists(cli)) GTEST_SKIP() << "nerfpt binary not built: " << cli;
    const fs::path dir = test::temp_dir();
    nerf::save_model(dir / "relit.npt", make_model(true), false);
    nerf::save_model(dir / "plain.npt", make_model(false), false);
    const std::string log = (dir / "log").string();
    const std::string relit = (dir / "relit.npt").string(), plain = (dir / "plain.npt").string();
    ASSERT_EQ(test::run_cli({"bake", relit, "-o", (dir / "a.vdb").string(), "--res", "16", "--threshold", "0",
                             "--colour", "albedo", "-q"},
                            log),
              0)
        << test::read_text(log);
    const media::VolumeGrid r = media::load_volume_grid(dir / "a.vdb", {});
    EXPECT_GT(r.nx, 0);

    struct Bad {
        std::vector<std::string> args;
        int code;
        std::string says;
    };
    const std::vector<Bad> bad = {
        {{"bake", plain, "-o", (dir / "b.vdb").string(), "--colour", "albedo"}, 1, "plain.npt: --colour albedo"},
        {{"bake", relit, "-o", (dir / "b.vdb").string(), "--colour", "normal"}, 2, "--colour"},
        {{"bake", relit, "-o", (dir / "b.vdb").string(), "--colour", "albedo", "--direction", "0,0,1"},
         1,
         "--direction"},
    };
    for (const auto& b : bad) {
        EXPECT_EQ(test::run_cli(b.args, log), b.code) << test::read_text(log);
        const std::string text = test::read_text(log);
        EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
        EXPECT_NE(text.find(b.says), std::string::npos) << text;
    }
    EXPECT_FALSE(fs::exists(dir / "b.vdb"));
}

}  // namespace
}  // namespace npt::bake
