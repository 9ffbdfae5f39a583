// `nerfpt train` killed with SIGKILL in the middle of a run leaves a loadable checkpoint, and --resume from it
// ends with exactly the model an uninterrupted run produces (same seed, same thread count).
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "nerf/model_file.h"
#include "nerf_test_scene.h"
#include "test_support.h"

namespace npt::nerf {
namespace {

namespace fs = std::filesystem;

using test::wait_exit;
fs::path cli() { return test::cli_binary(); }
std::string slurp(const fs::path& p) { return test::read_text(p); }
using test::spawn_cli;

TEST(TrainResume, SigkillThenResumeEqualsAnUninterruptedRun) {
    if (!fs::exists(cli())) GTEST_SKIP() << "nerfpt binary not built: " << cli();
    const fs::path dir = test::temp_dir();
    test::write_dataset(test::make_sphere_scene({.views = 8, .size = 16, .view_seed = 4}), dir / "data", 40.0f);
    test::write_file(dir / "config.json",
                     R"({"encoding": {"levels": 4, "log2_table_size": 12, "finest_resolution": 64},
                         "occupancy": {"resolution": 16, "update_interval": 4, "warmup_steps": 16},
                         "training": {"batch_samples": 2048}})");
    const std::string steps = "150";
    auto train = [&](const std::string& out, bool resume) {
        std::vector<std::string> a = {"train", (dir / "data").string(), "-o", out, "--steps",
                                      steps, "--threads", "2", "--checkpoint-every", "5", "-q"};
        if (resume)
            a.push_back("--resume");
        else
            a.insert(a.end(), {"--config", (dir / "config.json").string()});
        return a;
    };
    const fs::path ref = dir / "ref.npt", killed = dir / "killed.npt";
    ASSERT_EQ(wait_exit(spawn_cli(train(ref.string(), false), dir / "ref.log")), 0) << slurp(dir / "ref.log");

    // Kill once a checkpoint exists, mid-run.
    const int pid = spawn_cli(train(killed.string(), false), dir / "killed.log");
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (!fs::exists(killed) && std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    kill(pid, SIGKILL);
    ASSERT_EQ(wait_exit(pid), 128 + SIGKILL) << "the run ended before it could be killed: " << slurp(dir / "killed.log");

    const NerfModel partial = load_model(killed);  // a complete checkpoint, never a torn file
    ASSERT_TRUE(partial.training);
    const uint64_t stopped_at = partial.training->adam.step;
    EXPECT_GT(stopped_at, 0u);
    EXPECT_LT(stopped_at, 150u);

    ASSERT_EQ(wait_exit(spawn_cli(train(killed.string(), true), dir / "resume.log")), 0) << slurp(dir / "resume.log");
    const NerfModel a = load_model(ref), b = load_model(killed);
    ASSERT_EQ(a.training->adam.step, 150u);
    ASSERT_EQ(b.training->adam.step, 150u);
    EXPECT_EQ(a.params, b.params) << "resumed at step " << stopped_at;
    EXPECT_EQ(a.training->params, b.training->params);
    EXPECT_EQ(a.occupancy.density(), b.occupancy.density());
}

TEST(TrainResume, InterruptSavesACheckpointAndExits130) {
    if (!fs::exists(cli())) GTEST_SKIP() << "nerfpt binary not built: " << cli();
    const fs::path dir = test::temp_dir();
    test::write_dataset(test::make_sphere_scene({.views = 4, .size = 16, .view_seed = 5}), dir / "data", 40.0f);
    test::write_file(dir / "config.json",
                     R"({"encoding": {"levels": 4, "log2_table_size": 12, "finest_resolution": 64},
                         "occupancy": {"resolution": 16}, "training": {"batch_samples": 2048}})");
    const fs::path model = dir / "m.npt", log = dir / "train.log";
    // Checkpoints only every 100000 steps: the file can only come from the interrupt.
    const int pid = spawn_cli({"train", (dir / "data").string(), "-o", model.string(), "--config",
                             (dir / "config.json").string(), "--steps", "100000", "--checkpoint-every", "100000"},
                            log);
    // Wait until training runs (its first progress line), then interrupt it like Ctrl-C does.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (slurp(log).find("step") == std::string::npos && std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    kill(pid, SIGINT);
    EXPECT_EQ(wait_exit(pid), 130) << slurp(log);
    const std::string out = slurp(log);
    EXPECT_NE(out.find("--resume"), std::string::npos) << out;  // tells the user how to continue
    const NerfModel m = load_model(model);
    ASSERT_TRUE(m.training);
    EXPECT_GT(m.training->adam.step, 0u);
    EXPECT_LT(m.training->adam.step, 100000u);
}

}  // namespace
}  // namespace npt::nerf
