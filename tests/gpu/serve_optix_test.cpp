// The viewer on the OptiX backend: the page's views of the film's layers (beauty, alpha, normal, depth,
// albedo) come from OptiX's AOVs as they do from the CPU's (tests/unit/serve_server_test.cpp,
// ServeServer.ViewsShowTheFilmsLayers, the same scene, pixel and expected values).
#include <gtest/gtest.h>
#include <turbojpeg.h>

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

// The serve test scene (tests/data/serve) copied to a temporary folder: from the source tree, or from the
// working tree the GPU machine runs in (scripts/gpu_check.sh runs from its root).
fs::path copy_serve_scene() {
    fs::path src = fs::path(NERFPT_SOURCE_DIR) / "tests" / "data" / "serve";
    if (!fs::exists(src)) src = fs::path("tests") / "data" / "serve";
    if (!fs::exists(src)) return {};
    const fs::path dir = test::temp_dir();
    for (const auto& e : fs::directory_iterator(src)) fs::copy_file(e.path(), dir / e.path().filename());
    return dir / "scene.json";
}

std::array<int, 3> jpeg_pixel(const std::string& jpeg, int x, int y) {
    tjhandle tj = tjInitDecompress();
    int w = 0, h = 0, sub = 0, space = 0;
    std::vector<unsigned char> rgb;
    const auto* src = reinterpret_cast<const unsigned char*>(jpeg.data());
    if (tjDecompressHeader3(tj, src, jpeg.size(), &w, &h, &sub, &space) == 0) {
        rgb.resize(size_t(w) * h * 3);
        tjDecompress2(tj, src, jpeg.size(), rgb.data(), w, 0, h, TJPF_RGB, 0);
    }
    tjDestroy(tj);
    if (x >= w || y >= h) {
        ADD_FAILURE() << "pixel " << x << "," << y << " outside the " << w << "x" << h << " frame";
        return {-1, -1, -1};
    }
    const unsigned char* p = &rgb[(size_t(y) * w + x) * 3];
    return {p[0], p[1], p[2]};
}

TEST(ServeOptix, ViewsShowTheFilmsLayers) {
    if (!render::optix_backend_built()) GTEST_SKIP() << "built without the OptiX backend";
    const fs::path scene = copy_serve_scene();
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
            return jpeg_pixel(c.last_jpeg, 120, 60);
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
