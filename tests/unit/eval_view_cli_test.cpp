// `nerfpt eval` and `nerfpt view` end to end on a model trained for a few seconds on the sphere data set:
// eval's numbers are the ones render_view + ground_truth_image + psnr/ssim give for the same view, its files
// hold what they should (the comparison's ground-truth panel survives the sRGB handling to 8-bit rounding),
// view --camera reproduces eval's render, and the default orbit frames the model.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/image_io.h"
#include "core/image_metrics.h"
#include "core/mask_metrics.h"
#include "nerf/eval_images.h"
#include "nerf/model_file.h"
#include "nerf/render_view.h"
#include "nerf_test_scene.h"
#include "test_support.h"

namespace npt::nerf {
namespace {

namespace fs = std::filesystem;

using test::read_text;
using test::run_cli;
fs::path cli() { return test::cli_binary(); }
std::string slurp(const fs::path& p) { return read_text(p); }

// Each test trains its own model (a fraction of a second) in its own folder: ctest runs the tests as
// separate processes, possibly at once.
class EvalViewCli : public ::testing::Test {
  protected:
    void SetUp() override {
        if (!fs::exists(cli())) GTEST_SKIP() << "nerfpt binary not built: " << cli();
        m_dir = test::temp_dir();
        test::write_dataset(test::make_sphere_scene({.views = 12, .size = 32, .view_seed = 1}),
                            m_dir / "train", 40.0f);
        test::write_dataset(test::make_sphere_scene({.views = 3, .size = 32, .view_seed = 2}), m_dir / "test",
                            40.0f);
        test::write_file(m_dir / "config.json",
                         R"({"encoding": {"levels": 4, "log2_table_size": 12, "finest_resolution": 64},
                             "occupancy": {"resolution": 16, "update_interval": 4, "warmup_steps": 16},
                             "training": {"batch_samples": 2048}})");
        ASSERT_EQ(run_cli({"train", (m_dir / "train" / "transforms.json").string(), "-o",
                           (m_dir / "m.npt").string(), "--config", (m_dir / "config.json").string(),
                           "--steps", "100", "-q"},
                          m_dir / "train.log"),
                  0)
            << slurp(m_dir / "train.log");
    }
    const fs::path& dir() const { return m_dir; }
    fs::path test_json() const { return m_dir / "test" / "transforms.json"; }

    fs::path m_dir;
};

TEST_F(EvalViewCli, InfoDescribesAModel) {
    ASSERT_EQ(run_cli({"info", (dir() / "m.npt").string()}, dir() / "info.log"), 0)
        << slurp(dir() / "info.log");
    std::string out = slurp(dir() / "info.log");
    EXPECT_NE(out.find("hash grid 4 levels x 2 features, 2^12 entries"), std::string::npos) << out;
    EXPECT_NE(out.find("training   100 steps"), std::string::npos) << out;

    // Content bounds, from a model whose occupancy is one known block: model cells 4..7 of 16 along x
    // (0.25..0.5), 8..11 along y and z (0.5..0.75). Model x, y, z = world y, z, x (times 0.33, + 0.5), so the
    // block's cell centres span world x (z) 0.0947..0.6629, y (x) -0.6629..-0.0947, z (y) 0.0947..0.6629.
    nerf::NerfConfig c;
    c.encoding.grid.levels = 2;
    c.encoding.grid.log2_table_size = 10;
    c.occupancy.resolution = 16;
    nerf::NerfModel m = nerf::create_model(c, 1.0f, nerf::ngp_world_to_model(0.33f, Vec3(0.5f)));
    std::vector<float> d(16 * 16 * 16, 0.0f);
    for (int z = 8; z < 12; ++z)
        for (int y = 8; y < 12; ++y)
            for (int x = 4; x < 8; ++x) d[x + y * 16 + z * 256] = 1.0f;
    m.occupancy.set_density(d, c.occupancy.threshold);
    m.training.reset();
    nerf::save_model(dir() / "block.npt", m, false);
    ASSERT_EQ(run_cli({"info", (dir() / "block.npt").string()}, dir() / "info2.log"), 0);
    out = slurp(dir() / "info2.log");
    const size_t at = out.find("training world (");
    ASSERT_NE(at, std::string::npos) << out;
    float lo[3], hi[3];
    ASSERT_EQ(std::sscanf(out.c_str() + at, "training world (%f, %f, %f) .. (%f, %f, %f)", &lo[0], &lo[1],
                          &lo[2], &hi[0], &hi[1], &hi[2]),
              6)
        << out;
    const float expect_lo[3] = {0.0947f, -0.6629f, 0.0947f}, expect_hi[3] = {0.6629f, -0.0947f, 0.6629f};
    for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(lo[a], expect_lo[a], 2e-3f) << out;  // printed with 3 significant digits
        EXPECT_NEAR(hi[a], expect_hi[a], 2e-3f) << out;
    }
    EXPECT_NE(out.find("no training state"), std::string::npos) << out;
}

TEST_F(EvalViewCli, EvalNumbersAndFiles) {
    const fs::path out = dir() / "eval";  // created by eval
    ASSERT_EQ(run_cli({"eval", (dir() / "m.npt").string(), test_json().string(), "-o", out.string(), "-q"},
                      dir() / "eval.log"),
              0)
        << slurp(dir() / "eval.log");
    const std::string log = slurp(dir() / "eval.log");
    EXPECT_NE(log.find("mean over 3 views"), std::string::npos) << log;

    const nlohmann::json m = nlohmann::json::parse(slurp(out / "metrics.json"));
    ASSERT_EQ(m.at("images").size(), 3u);
    EXPECT_EQ(m.at("data"), test_json().string());
    const NerfModel model = load_model(dir() / "m.npt");
    const Dataset test = load_dataset(test_json(), "");
    double sum_psnr = 0, sum_ssim = 0;
    for (size_t k = 0; k < 3; ++k) {
        const nlohmann::json& e = m.at("images")[k];
        const std::string name = e.at("name");
        EXPECT_EQ(name, "r_" + std::to_string(k));
        // The same numbers as the library gives for the same view (the render is deterministic).
        const Image render = render_view(model, test.cameras[k], {});
        const Image truth = ground_truth_image(test, k, Rgb(1.0f, 1.0f, 1.0f));
        EXPECT_DOUBLE_EQ(e.at("psnr").get<double>(), psnr(render, truth)) << name;
        EXPECT_DOUBLE_EQ(e.at("ssim").get<double>(), ssim(render, truth)) << name;
        EXPECT_TRUE(std::isfinite(e.at("psnr").get<double>())) << name;
        sum_psnr += e.at("psnr").get<double>();
        sum_ssim += e.at("ssim").get<double>();

        const Image png = read_image(out / (name + ".png"), /*srgb=*/false);
        const Image strip = read_image(out / (name + "_compare.png"), /*srgb=*/false);
        ASSERT_EQ(png.width, 32);
        ASSERT_EQ(strip.width, 96);
        ASSERT_EQ(strip.height, 32);
        // Written values are the encoded values as they are: 8-bit rounding is the only change.
        float worst = 0;
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x)
                for (int c = 0; c < 3; ++c) {
                    worst = std::max(worst, std::abs(strip.at(x, y)[c] - truth.at(x, y)[c]));
                    worst = std::max(worst, std::abs(strip.at(32 + x, y)[c] - render.at(x, y)[c]));
                    worst = std::max(worst, std::abs(png.at(x, y)[c] - render.at(x, y)[c]));
                }
        EXPECT_LE(worst, 0.5f / 255.0f + 1e-5f) << name;
    }
    EXPECT_NEAR(m.at("mean").at("psnr").get<double>(), sum_psnr / 3, 1e-12);
    EXPECT_NEAR(m.at("mean").at("ssim").get<double>(), sum_ssim / 3, 1e-12);

    // --every 2 evaluates views 0 and 2 only.
    ASSERT_EQ(run_cli({"eval", (dir() / "m.npt").string(), test_json().string(), "--every", "2", "-q"},
                      dir() / "every.log"),
              0);
    const std::string every = slurp(dir() / "every.log");
    EXPECT_NE(every.find("r_0 "), std::string::npos) << every;
    EXPECT_EQ(every.find("r_1 "), std::string::npos) << every;
    EXPECT_NE(every.find("r_2 "), std::string::npos) << every;
}

// --masks: the sphere set's own RGBA frames are masks (their alpha is the objects' coverage), so the test
// folder serves as DIR. The numbers are score_mask's for the render's alpha (this 100-step model is crude:
// IoU about 0.05, only in range); the model's own alpha maps (--alpha) as masks score a perfect IoU and F.
TEST_F(EvalViewCli, EvalMasksAndAlpha) {
    const fs::path out = dir() / "masks_eval";
    const std::string model = (dir() / "m.npt").string();
    ASSERT_EQ(run_cli({"eval", model, test_json().string(), "--masks", (dir() / "test").string(), "--alpha",
                       "-o", out.string(), "-q"},
                      dir() / "eval.log"),
              0)
        << slurp(dir() / "eval.log");
    const std::string log = slurp(dir() / "eval.log");
    EXPECT_NE(log.find("iou "), std::string::npos) << log;
    EXPECT_NE(log.find("leak "), std::string::npos) << log;
    const nlohmann::json m = nlohmann::json::parse(slurp(out / "metrics.json"));
    EXPECT_EQ(m.at("boundary_tolerance_px"), 1);
    const NerfModel nm = load_model(dir() / "m.npt");
    const Dataset test = load_dataset(test_json(), "");
    double sum_iou = 0;
    for (size_t k = 0; k < 3; ++k) {
        const nlohmann::json& e = m.at("images")[k].at("mask");
        const Image render = render_view(nm, test.cameras[k], {});
        Coverage alpha{32, 32, std::vector<float>(32 * 32)};
        for (size_t p = 0; p < alpha.values.size(); ++p) alpha.values[p] = render.pixels[p * 4 + 3];
        const Mask truth = threshold_coverage(read_coverage(test.image_files[k]));
        const MaskScores want = score_mask(alpha, truth);
        EXPECT_DOUBLE_EQ(e.at("iou").get<double>(), want.iou) << k;
        EXPECT_DOUBLE_EQ(e.at("boundary_f").get<double>(), want.boundary.f) << k;
        EXPECT_DOUBLE_EQ(e.at("leak").get<double>(), want.leak) << k;
        // Every view of the sphere set shows a sphere: the mask is never empty, so the value is never null.
        ASSERT_TRUE(e.at("alpha_inside").is_number()) << k;
        EXPECT_DOUBLE_EQ(e.at("alpha_inside").get<double>(), mask_coverage_inside(alpha, truth)) << k;
        for (double v : {want.iou, want.boundary.f, want.leak}) {
            EXPECT_GE(v, 0.0) << k;
            EXPECT_LE(v, 1.0) << k;
        }
        sum_iou += want.iou;
        const Image png = read_image(out / ("r_" + std::to_string(k) + "_alpha.png"), /*srgb=*/false);
        ASSERT_EQ(png.width, 32);
        float worst = 0;
        for (size_t p = 0; p < alpha.values.size(); ++p)
            worst = std::max(worst, std::abs(png.pixels[p * 3] - alpha.values[p]));
        EXPECT_LE(worst, 0.5f / 255.0f + 1e-5f) << k;
    }
    EXPECT_NEAR(m.at("mean").at("mask").at("iou").get<double>(), sum_iou / 3, 1e-12);

    const fs::path own = dir() / "own_alpha";
    fs::create_directories(own);
    for (int k = 0; k < 3; ++k)
        fs::copy_file(out / ("r_" + std::to_string(k) + "_alpha.png"),
                      own / ("r_" + std::to_string(k) + ".png"));
    ASSERT_EQ(
        run_cli({"eval", model, test_json().string(), "--masks", own.string(), "-q"}, dir() / "own.log"), 0)
        << slurp(dir() / "own.log");
    EXPECT_NE(slurp(dir() / "own.log").find("iou 1.0000  bf 1.0000"), std::string::npos)
        << slurp(dir() / "own.log");

    // A missing mask: one line naming the file, before any render is written.
    const fs::path masks = dir() / "masks";
    fs::create_directories(masks);
    fs::copy_file(dir() / "test" / "r_0.png", masks / "r_0.png");
    fs::copy_file(dir() / "test" / "r_2.png", masks / "r_2.png");
    const fs::path bad_out = dir() / "bad_eval";
    EXPECT_EQ(run_cli({"eval", model, test_json().string(), "--masks", masks.string(), "-o", bad_out.string(),
                       "-q"},
                      dir() / "missing.log"),
              1);
    std::string err = slurp(dir() / "missing.log");
    EXPECT_NE(err.find((masks / "r_1.png").string() + ": not found"), std::string::npos) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_FALSE(fs::exists(bad_out / "r_0.png"));
    EXPECT_FALSE(fs::exists(bad_out / "metrics.json"));
    // The wrong size, and a file that is no PNG.
    write_png(masks / "r_1.png", Image(16, 16));
    EXPECT_EQ(run_cli({"eval", model, test_json().string(), "--masks", masks.string()}, dir() / "size.log"),
              1);
    err = slurp(dir() / "size.log");
    EXPECT_NE(err.find("r_1.png: mask is 16x16, the view (r_1.png) is 32x32"), std::string::npos) << err;
    test::write_file(masks / "r_1.png", "no png");
    EXPECT_EQ(
        run_cli({"eval", model, test_json().string(), "--masks", masks.string(), "-q"}, dir() / "bad.log"),
        1);
    err = slurp(dir() / "bad.log");
    EXPECT_NE(err.find("r_1.png: not a readable image"), std::string::npos) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    // A missing folder; --alpha without -o has nowhere to write.
    EXPECT_EQ(run_cli({"eval", model, test_json().string(), "--masks", (dir() / "nope").string()},
                      dir() / "nodir.log"),
              1);
    EXPECT_NE(slurp(dir() / "nodir.log").find("nope"), std::string::npos) << slurp(dir() / "nodir.log");
    EXPECT_EQ(run_cli({"eval", model, test_json().string(), "--alpha"}, dir() / "alpha.log"), 2);
}

TEST_F(EvalViewCli, ViewCameraMatchesTheRender) {
    const fs::path png = dir() / "cam1.png";
    ASSERT_EQ(run_cli({"view", (dir() / "m.npt").string(), "-o", png.string(), "--camera",
                       test_json().string() + ":1", "-q"},
                      dir() / "view_cam.log"),
              0)
        << slurp(dir() / "view_cam.log");
    const NerfModel model = load_model(dir() / "m.npt");
    const Dataset test = load_dataset(test_json(), "");
    const Image render = render_view(model, test.cameras[1], {});
    const Image img = read_image(png, /*srgb=*/false);
    ASSERT_EQ(img.width, 32);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x)
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(img.at(x, y)[c], render.at(x, y)[c], 0.5f / 255.0f + 1e-5f);
    // --res rescales the intrinsics: the same view at twice the size.
    ASSERT_EQ(run_cli({"view", (dir() / "m.npt").string(), "-o", png.string(), "--camera",
                       test_json().string() + ":1", "--res", "64x64", "-q"},
                      dir() / "view_cam.log"),
              0);
    EXPECT_EQ(read_image(png).width, 64);
}

TEST_F(EvalViewCli, DefaultOrbitFramesTheModel) {
    ASSERT_EQ(run_cli({"view", (dir() / "m.npt").string(), "-o", (dir() / "spin.png").string(), "--orbit",
                       "3", "--res", "24x16", "-q"},
                      dir() / "orbit.log"),
              0)
        << slurp(dir() / "orbit.log");
    for (int k = 0; k < 3; ++k) {
        const fs::path f = dir() / ("spin_000" + std::to_string(k) + ".png");
        ASSERT_TRUE(fs::exists(f)) << f;
        const Image img = read_image(f, /*srgb=*/false);
        EXPECT_EQ(img.width, 24);
        EXPECT_EQ(img.height, 16);
        // The spheres lie within radius 1 of the origin and the default orbit sits 4 away, as the training
        // cameras did: the model fills part of the frame (not none of it, not all of it).
        int covered = 0;
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 24; ++x)
                covered += img.at(x, y)[0] + img.at(x, y)[1] + img.at(x, y)[2] < 2.7f;
        EXPECT_GT(covered, 24 * 16 / 20) << f;
        EXPECT_LT(covered, 24 * 16 * 4 / 5) << f;
    }
    // A real video needs ffmpeg; where it is installed, check that one comes out.
    if (std::system("command -v ffmpeg >/dev/null 2>&1") == 0) {
        const fs::path mp4 = dir() / "spin.mp4";
        ASSERT_EQ(run_cli({"view", (dir() / "m.npt").string(), "-o", mp4.string(), "--orbit", "3", "--res",
                           "24x16", "-q"},
                          dir() / "mp4.log"),
                  0)
            << slurp(dir() / "mp4.log");
        EXPECT_GT(fs::file_size(mp4), 0u);
    }
}

// The .mp4 path with a stand-in ffmpeg on PATH that records how it was called: the command line of the brief,
// every frame in the folder it is given, that folder gone afterwards; and ffmpeg's own error reaches the user
// on one line.
TEST_F(EvalViewCli, VideoGoesThroughFfmpegAndCleansUp) {
    const fs::path bin = dir() / "bin";
    fs::create_directories(bin);
    const fs::path record = dir() / "ffmpeg_args.txt";
    test::write_file(bin / "ffmpeg",
                     "#!/bin/sh\n"
                     "echo \"$@\" > '" +
                         record.string() +
                         "'\n"
                         "for a; do last=$a; done\n"
                         "while [ $# -gt 0 ]; do [ \"$1\" = -i ] && in=$2; shift; done\n"
                         "frames=$(dirname \"$in\")\n"
                         "echo \"$frames\" >> '" +
                         record.string() +
                         "'\n"
                         "ls \"$frames\" | grep -c '^frame_[0-9]*\\.png$' >> '" +
                         record.string() +
                         "'\n"
                         "[ -n \"$FAIL\" ] && { echo \"Unknown encoder 'libx264'\" >&2; exit 1; }\n"
                         "echo video > \"$last\"\n");
    fs::permissions(bin / "ffmpeg", fs::perms::owner_all);
    const std::string path = bin.string() + ":/usr/bin:/bin";
    const fs::path mp4 = dir() / "spin.mp4";
    ASSERT_EQ(run_cli({"view", (dir() / "m.npt").string(), "-o", mp4.string(), "--orbit", "3", "--res",
                       "24x16", "--fps", "12", "-q"},
                      dir() / "mp4.log", path),
              0)
        << slurp(dir() / "mp4.log");
    EXPECT_EQ(slurp(mp4), "video\n");
    std::ifstream f(record);
    std::string args, frames, count;
    std::getline(f, args);
    std::getline(f, frames);
    std::getline(f, count);
    EXPECT_NE(args.find("-y"), std::string::npos) << args;
    EXPECT_NE(args.find("-framerate 12 -i " + frames + "/frame_%04d.png -pix_fmt yuv420p -c:v libx264 " +
                        mp4.string()),
              std::string::npos)
        << args;
    EXPECT_EQ(count, "3");
    EXPECT_FALSE(fs::exists(frames)) << "temporary frames left in " << frames;

    // A failing ffmpeg: exit code 1, its message on one line, the frames cleaned up all the same.
    setenv("FAIL", "1", 1);
    const int rc = run_cli(
        {"view", (dir() / "m.npt").string(), "-o", mp4.string(), "--orbit", "2", "--res", "24x16", "-q"},
        dir() / "fail.log", path);
    unsetenv("FAIL");
    EXPECT_EQ(rc, 1);
    const std::string log = slurp(dir() / "fail.log");
    EXPECT_NE(log.find("nerfpt: error: ffmpeg failed"), std::string::npos) << log;
    EXPECT_NE(log.find("Unknown encoder 'libx264'"), std::string::npos) << log;
    EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 1) << log;
    std::ifstream f2(record);
    std::getline(f2, args);
    std::getline(f2, frames);
    EXPECT_FALSE(fs::exists(frames)) << "temporary frames left in " << frames;
}

// No command writes over one of its own inputs, --force or not (train -o DATA/transforms.json --force used to
// replace the data set with a model; eval -o DATA/test writes NAME.png over the ground truth).
TEST_F(EvalViewCli, NoCommandWritesOverItsInputs) {
    const fs::path test_dir = dir() / "test";
    std::vector<fs::path> inputs{test_json()};
    for (const auto& e : fs::directory_iterator(test_dir))
        if (e.path().extension() == ".png") inputs.push_back(e.path());
    ASSERT_GT(inputs.size(), 1u);
    std::vector<std::string> before;
    for (const auto& p : inputs) before.push_back(slurp(p));
    const fs::path log = dir() / "overwrite.log";
    const std::string model = (dir() / "m.npt").string();

    EXPECT_EQ(run_cli({"train", test_json().string(), "-o", test_json().string(), "--force", "-q"}, log), 1);
    EXPECT_NE(slurp(log).find("is the input DATA"), std::string::npos) << slurp(log);
    EXPECT_EQ(
        run_cli({"train", test_dir.string(), "--split", "", "-o", inputs[1].string(), "--force", "-q"}, log),
        1);
    EXPECT_NE(slurp(log).find("is the input DATA's image of frame"), std::string::npos) << slurp(log);
    EXPECT_EQ(run_cli({"eval", model, test_json().string(), "-o", test_dir.string(), "-q"}, log), 1);
    EXPECT_NE(slurp(log).find("is the input DATA's image of frame 0"), std::string::npos) << slurp(log);
    EXPECT_EQ(
        run_cli({"view", model, "-o", inputs[1].string(), "--camera", test_json().string() + ":0", "-q"},
                log),
        1);
    EXPECT_NE(slurp(log).find("is the input DATA's image"), std::string::npos) << slurp(log);
    fs::copy_file(model, dir() / "model.vdb");  // a model file under a grid's name: bake it over itself
    EXPECT_EQ(
        run_cli({"bake", (dir() / "model.vdb").string(), "-o", (dir() / "model.vdb").string(), "-q"}, log),
        1);
    EXPECT_NE(slurp(log).find("is the input MODEL"), std::string::npos) << slurp(log);
    for (size_t i = 0; i < inputs.size(); ++i) EXPECT_EQ(slurp(inputs[i]), before[i]) << inputs[i];
    EXPECT_FALSE(fs::exists(test_dir / "metrics.json"));
    // NaN is not a number of seconds: a usage error, no 0-step model.
    EXPECT_EQ(
        run_cli({"train", test_json().string(), "-o", (dir() / "nan.npt").string(), "--time", "nan"}, log),
        2);
    EXPECT_FALSE(fs::exists(dir() / "nan.npt"));
}

}  // namespace
}  // namespace npt::nerf
