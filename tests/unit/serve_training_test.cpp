// The live-training page's machinery end to end in one process: a tiny model trained on the CPU for a few
// steps with a TrainingMonitor as its observer, served by the Server; a Boost.Beast WebSocket client gets the
// training status with a finite PSNR, a held-out evaluation with its strip (a JPEG), an orbit render from a
// camera it sends, errors for other messages, and a second page starts from the whole state.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <thread>

#include "nerf/backend/nerf_backend.h"
#include "nerf_test_scene.h"
#include "serve/server.h"
#include "serve/training_monitor.h"
#include "serve_test_client.h"
#include "test_support.h"

namespace npt::serve {
namespace {
namespace fs = std::filesystem;
using json = nlohmann::json;

using Client = test::ServeClient;

bool finite_number(const json& j) { return j.is_number() && std::isfinite(j.get<double>()); }

TEST(ServeTraining, PageGetsStatusHeldOutStripAndOrbitWhileACpuModelTrains) {
    // The data folder: 12 training views (transforms.json) and 3 held-out ones (transforms_test.json).
    const fs::path dir = test::temp_dir();
    nerf::Dataset held = test::make_sphere_scene({.views = 3, .size = 32, .view_seed = 2});
    for (std::string& n : held.names) n = "test_" + n;
    test::write_dataset(held, dir, 40.0f);
    fs::rename(dir / "transforms.json", dir / "transforms_test.json");
    const nerf::Dataset train = test::make_sphere_scene({.views = 12, .size = 32, .view_seed = 1});
    test::write_dataset(train, dir, 40.0f);

    ServerOptions so;
    so.port = 0;
    so.index = "/train.html";
    Server server(so);
    TrainingMonitorOptions mo;
    mo.title = "test";
    mo.eval_views = 2;
    mo.min_eval_interval = 0.2;
    mo.max_eval_share = 0.5;
    mo.status_interval = 0.1;
    mo.view_side = 48;
    TrainingMonitor monitor(mo, server);
    server.attach(&monitor);
    monitor.start();
    std::thread io([&] { server.run(); });

    Client page(server.port());
    EXPECT_EQ(page.until("state")["mode"], "train");

    nerf::NerfModel model = nerf::create_model(test::small_sphere_config(), train.aabb_scale,
                                               nerf::ngp_world_to_model(train.scale, train.offset));
    auto trainer = nerf::make_trainer(nerf::Backend::cpu, model, train);
    nerf::TrainingStart ts;
    ts.data = &train;
    ts.data_path = dir.string();
    ts.split = "train";
    ts.world_to_model = model.world_to_model;
    ts.backend = nerf::Backend::cpu;
    ts.target_steps = 400;
    monitor.on_start(ts);
    // Steps until the monitor asked for a snapshot during training and evaluated it (a few at most).
    const auto t0 = std::chrono::steady_clock::now();
    int snapshots = 0;
    while (trainer->steps_done() < 400 && (monitor.evals_done() < 2 || trainer->steps_done() < 10) &&
           std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60)) {
        const nerf::StepStats s = trainer->step();
        monitor.on_step(s, model.training->elapsed_seconds, double(trainer->steps_done()) / 400.0);
        if (monitor.snapshot_due()) {
            trainer->sync_model();
            monitor.on_snapshot(model, trainer->steps_done());
            ++snapshots;
        }
    }
    EXPECT_GE(snapshots, 1);
    EXPECT_GE(monitor.evals_done(), 1u);

    const json status = page.until(
        "train", [](const json& m) { return m["step"].get<uint64_t>() > 0 && finite_number(m["psnr"]); });
    EXPECT_GT(status["step"].get<uint64_t>(), 0u);
    EXPECT_TRUE(finite_number(status["loss"]));
    EXPECT_FALSE(status["points"]["step"].empty());
    const json eval = page.until("eval");
    EXPECT_TRUE(finite_number(eval["psnr"])) << eval["psnr"];
    EXPECT_EQ(eval["split"], "test");
    EXPECT_EQ(eval["views"].size(), 2u);
    const std::string strip = eval["strip"].get<std::string>();
    EXPECT_GT(strip.size(), 200u);
    EXPECT_EQ(strip.substr(0, 4), "/9j/");  // base64 of a JPEG's FF D8 FF
    EXPECT_EQ(eval["strip_width"], 3 * 32);

    // The page orbits: a render of the current model from its camera.
    page.send(
        R"({"type": "camera", "position": [0, -4, 0.5], "forward": [0, 1, -0.1], "up": [0, 0, 1], "fov_deg": 40})");
    const json frame = page.until("frame");
    EXPECT_EQ(frame["view"], "orbit");
    EXPECT_GT(frame["jpeg_bytes"].get<size_t>(), 100u);
    EXPECT_EQ(frame["width"], 48);
    // Bad input: an error, and the page goes on; a malformed message too.
    page.send(R"({"type": "save"})");
    EXPECT_NE(page.until("error")["message"].get<std::string>().find("camera messages only"),
              std::string::npos);
    page.send("{not json");
    EXPECT_NE(page.until("error")["message"].get<std::string>().find("not valid JSON"), std::string::npos);

    trainer->sync_model();
    monitor.on_snapshot(model, trainer->steps_done());
    monitor.on_finish(trainer->steps_done(), model.training->elapsed_seconds, false);
    page.until("train", [](const json& m) { return m["finished"].get<bool>(); });

    // A second page starts from everything so far; an oversized message closes only that page.
    {
        Client second(server.port());
        const json st = second.until("state");
        EXPECT_FALSE(st["history"]["step"].empty());
        EXPECT_FALSE(st["evals"].empty());
        EXPECT_FALSE(st["strip"].get<std::string>().empty());
        EXPECT_EQ(st["held_out"]["split"], "test");
        EXPECT_TRUE(st["finished"].get<bool>());
        second.send(std::string(k_max_message_bytes + 10, ' '));
        EXPECT_THROW(for (int i = 0; i < 10000; ++i) second.next(), boost::system::system_error);
    }
    for (int i = 0; i < 200 && server.sessions() > 1; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    EXPECT_EQ(server.sessions(), 1u);  // the closed page's session is gone, the first one stays
    page.send(R"({"type": "camera", "position": [0, -4, 1], "forward": [0, 1, -0.2], "up": [0, 0, 1]})");
    EXPECT_EQ(page.until("frame")["view"], "orbit");

    monitor.stop();
    server.stop();
    io.join();
    EXPECT_GT(monitor.eval_seconds_total(), 0.0);
}

TEST(ServeTraining, Base64MatchesRfc4648) {
    EXPECT_EQ(base64_encode(""), "");
    EXPECT_EQ(base64_encode("f"), "Zg==");
    EXPECT_EQ(base64_encode("fo"), "Zm8=");
    EXPECT_EQ(base64_encode("foo"), "Zm9v");
    EXPECT_EQ(base64_encode("foobar"), "Zm9vYmFy");
    EXPECT_EQ(base64_encode(std::string("\xff\xd8\xff", 3)), "/9j/");
}

}  // namespace
}  // namespace npt::serve
