// The viewer on the OptiX backend: the page's views of the film's layers (beauty, alpha, normal, depth,
// albedo) come from OptiX's AOVs as they do from the CPU's (tests/unit/serve_server_test.cpp,
// ServeServer.ViewsShowTheFilmsLayers, the same scene, pixel and expected values).
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <thread>

#include "render/backend/render_backend.h"
#include "serve/server.h"
#include "serve/viewer.h"
#include "serve_test_client.h"
#include "test_support.h"

namespace npt::serve {
namespace {
namespace fs = std::filesystem;
using json = nlohmann::json;

TEST(ServeOptix, ViewsShowTheFilmsLayers) {
    if (!render::optix_backend_built()) GTEST_SKIP() << "built without the OptiX backend";
    const fs::path scene = test::copy_serve_scene();
    if (scene.empty()) GTEST_SKIP() << "tests/data/serve not found";
    ServerOptions so;
    so.port = 0;
    Server server(so);
    ViewerOptions vo;
    vo.scene = scene;
    vo.backend = "optix";
    vo.preview_divisor = 2;
    Viewer viewer(vo, server);
    server.attach(&viewer);
    viewer.start();
    std::thread thread([&] { server.run(); });
    {
        test::ServeClient c(server.port());
        const auto settled = [&](const std::string& view) {
            c.until("state", [&](const json& s) { return s["view"] == view; });
            c.until("frame", [](const json& f) { return f["spp"] == 4 && !f["preview"].get<bool>(); });
            return test::jpeg_pixel(c.last_jpeg, 120, 60);
        };
        const auto near = [](std::array<int, 3> got, std::array<int, 3> want) {
            for (int i = 0; i < 3; ++i)
                if (std::abs(got[size_t(i)] - want[size_t(i)]) > 6) return false;
            return true;
        };
        std::array<int, 3> px = settled("beauty");
        EXPECT_TRUE(near(px, {188, 137, 99})) << px[0] << " " << px[1] << " " << px[2];
        c.send(R"({"type": "settings", "view": "alpha"})");
        px = settled("alpha");
        EXPECT_TRUE(near(px, {255, 255, 255})) << px[0] << " " << px[1] << " " << px[2];
        c.send(R"({"type": "settings", "view": "normal"})");
        px = settled("normal");
        EXPECT_TRUE(near(px, {128, 128, 255})) << px[0] << " " << px[1] << " " << px[2];
        c.send(R"({"type": "settings", "view": "depth"})");
        px = settled("depth");
        EXPECT_EQ(px[0], px[1]);
        EXPECT_NEAR(px[0], 50, 6);  // derived in ServeServer.ViewsShowTheFilmsLayers
        c.send(R"({"type": "settings", "view": "albedo"})");
        px = settled("albedo");
        EXPECT_TRUE(near(px, {0, 0, 0})) << px[0] << " " << px[1] << " " << px[2];
    }
    viewer.stop();
    server.stop();
    thread.join();
}

}  // namespace
}  // namespace npt::serve
