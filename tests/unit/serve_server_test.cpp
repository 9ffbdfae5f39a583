// nerfpt serve end to end in one process, through a Boost.Beast WebSocket client: the page's first state and
// frames, a camera message giving a frame from the new camera, bad messages answered with errors while the
// server goes on, a closed page freeing its session, the token, and an edit saved then rendered by `nerfpt
// render` with the object where it was placed.
#include <gtest/gtest.h>

#include <array>
#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <thread>

#include "core/image_io.h"
#include "serve/server.h"
#include "serve/viewer.h"
#include "serve_test_client.h"
#include "test_support.h"

namespace npt::serve {
namespace {
namespace fs = std::filesystem;
namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = asio::ip::tcp;
using json = nlohmann::json;

// A viewer and its server on a free port, served by a thread.
struct Running {
    std::unique_ptr<Server> server;
    std::unique_ptr<Viewer> viewer;
    std::thread thread;
    Running(const fs::path& scene, const std::string& token = {}) {
        ServerOptions so;
        so.port = 0;
        so.token = token;
        server = std::make_unique<Server>(so);
        ViewerOptions vo;
        vo.scene = scene;
        vo.preview_divisor = 2;
        viewer = std::make_unique<Viewer>(vo, *server);
        server->attach(viewer.get());
        viewer->start();
        thread = std::thread([this] { server->run(); });
    }
    ~Running() {
        viewer->stop();
        server->stop();
        thread.join();
    }
};

using Client = test::ServeClient;
using test::copy_serve_scene;
using test::jpeg_pixel;

int http_get(uint16_t port, const std::string& target, const std::string& host = {}) {
    asio::io_context ioc;
    beast::tcp_stream stream(ioc);
    tcp::resolver resolver(ioc);
    stream.connect(resolver.resolve("127.0.0.1", std::to_string(port)));
    http::request<http::string_body> req{http::verb::get, target, 11};
    req.set(http::field::host, host.empty() ? "127.0.0.1:" + std::to_string(port) : host);
    http::write(stream, req);
    beast::flat_buffer b;
    http::response<http::string_body> res;
    http::read(stream, b, res);
    return int(res.result_int());
}

TEST(ServeServer, PageGetsStateAndFramesAndACameraMoveGivesANewFrame) {
    Running r(copy_serve_scene());
    EXPECT_EQ(http_get(r.server->port(), "/"), 200);
    EXPECT_EQ(http_get(r.server->port(), "/nothing.js"), 404);
    EXPECT_EQ(http_get(r.server->port(), "/", "evil.example:80"), 403);  // DNS rebinding
    Client c(r.server->port());
    const json state = c.until("state");
    EXPECT_EQ(state["width"], 160);
    EXPECT_EQ(state["volumes"].size(), 1u);
    EXPECT_EQ(state["volumes"][0]["name"], "cube");
    const json first = c.until("frame");
    EXPECT_GT(first["jpeg_bytes"].get<size_t>(), 100u);
    // Accumulates to the scene's 4 spp at full resolution.
    const json done =
        c.until("frame", [](const json& f) { return f["spp"] == 4 && !f["preview"].get<bool>(); });
    EXPECT_EQ(done["width"], 160);

    c.send(
        R"({"type": "camera", "position": [0.5, 0, 5], "forward": [0, 0, -1], "up": [0, 1, 0], "fov_deg": 40})");
    const json moved = c.until("frame", [](const json& f) {
        return std::abs(f["camera"]["position"][0].get<double>() - 0.5) < 1e-6;
    });
    EXPECT_TRUE(moved["preview"].get<bool>());  // the first frame after a move is the reduced one
    EXPECT_EQ(moved["width"], 80);
    EXPECT_TRUE(moved.contains("latency_ms"));
    EXPECT_GT(moved["samples_per_s"].get<double>(), 0.0);
}

// The test scene's wall (z = -2, facing the camera at z = 5; the cube is left of centre) in each view, at the
// pixel right of centre, settled at the scene's 4 spp: beauty its emission, alpha 1, normal +z -> (0.5, 0.5,
// 1), depth a dark grey (computed below). JPEG and the 8-bit steps allow a few code
// values.
TEST(ServeServer, ViewsShowTheFilmsLayers) {
    Running r(copy_serve_scene());
    Client c(r.server->port());
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
    EXPECT_TRUE(near(px, {188, 137, 99}))
        << px[0] << " " << px[1] << " " << px[2];  // sRGB of (0.5, 0.25, 0.125)
    c.send(R"({"type": "settings", "view": "alpha"})");
    px = settled("alpha");
    EXPECT_TRUE(near(px, {255, 255, 255})) << px[0] << " " << px[1] << " " << px[2];
    c.send(R"({"type": "settings", "view": "normal"})");
    px = settled("normal");
    EXPECT_TRUE(near(px, {128, 128, 255})) << px[0] << " " << px[1] << " " << px[2];
    c.send(R"({"type": "settings", "view": "depth"})");
    px = settled("depth");
    // Depth: the wall (plane z = -2, 7 from the camera; focal length 60 / tan 20deg = 164.8 px) at pixel
    // (120.5, 60.5) is 7 sqrt(1 + (40.5 / 164.8)^2) = 7.21 away; the range is 1.1 x the farthest depth of the
    // first pass after the change, the preview (80x60): its corner pixel 7 sqrt(1 + (39.5^2 + 29.5^2)
    // / 82.4^2) = 8.16 -> 8.97. Shown: 1 - 7.21 / 8.97 = 0.197 -> 50.
    EXPECT_EQ(px[0], px[1]);
    EXPECT_NEAR(px[0], 50, 6);
    c.send(R"({"type": "settings", "view": "albedo"})");
    px = settled("albedo");
    EXPECT_TRUE(near(px, {0, 0, 0})) << px[0] << " " << px[1] << " " << px[2];  // the wall's Kd is 0
}

TEST(ServeServer, BadMessagesGetErrorsAndTheServerGoesOn) {
    Running r(copy_serve_scene());
    {
        Client c(r.server->port());
        c.until("state");
        c.send("{not json");
        EXPECT_NE(c.until("error")["message"].get<std::string>().find("not valid JSON"), std::string::npos);
        c.send(R"({"type": "volume", "index": 7, "translation": [0, 0, 0]})");
        EXPECT_NE(c.until("error")["message"].get<std::string>().find("volume.index"), std::string::npos);
        c.send(
            R"({"type": "volume", "index": 0, "translation": [1e8, 0, 0]})");  // parses; beyond no bound here
        c.send(R"({"type": "use_camera", "index": 3})");
        EXPECT_NE(c.until("error")["message"].get<std::string>().find("use_camera.index"), std::string::npos);
        // Oversized: the server closes this page's socket.
        c.send(std::string(k_max_message_bytes + 10, ' '));
        EXPECT_THROW(for (int i = 0; i < 10000; ++i) c.next(), boost::system::system_error);
    }
    // A closed page frees its session.
    for (int i = 0; i < 200 && r.server->sessions() > 0; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    EXPECT_EQ(r.server->sessions(), 0u);
    // Two pages at once: each has its own camera and gets the frames of its own view only.
    Client a(r.server->port()), b(r.server->port());
    a.until("state");
    b.until("state");
    a.send(R"({"type": "camera", "position": [0, 0.5, 5], "forward": [0, 0, -1]})");
    b.send(R"({"type": "camera", "position": [0, -0.5, 5], "forward": [0, 0, -1]})");
    const auto at_height = [](double y) {
        return [y](const json& f) { return std::abs(f["camera"]["position"][1].get<double>() - y) < 1e-6; };
    };
    const auto settled = [](double y) {
        return [y](const json& f) {
            return std::abs(f["camera"]["position"][1].get<double>() - y) < 1e-6 && f["spp"] == 4 &&
                   !f["preview"].get<bool>();
        };
    };
    // Every frame up to its own settled view: the page's start camera (y = 0) or its own move, never the
    // other page's.
    for (auto [client, own, other] : {std::tuple{&a, 0.5, -0.5}, std::tuple{&b, -0.5, 0.5}}) {
        json f;
        do {
            f = client->until("frame");
            EXPECT_FALSE(at_height(other)(f)) << f.dump();
        } while (!settled(own)(f) && !::testing::Test::HasFailure());
    }
    EXPECT_EQ(r.server->sessions(), 2u);
}

TEST(ServeServer, TokenIsRequiredWhenSet) {
    Running r(copy_serve_scene(), "abc123");
    EXPECT_EQ(http_get(r.server->port(), "/"), 403);
    EXPECT_EQ(http_get(r.server->port(), "/?token=abc12"), 403);
    EXPECT_EQ(http_get(r.server->port(), "/?token=abc123"), 200);
    EXPECT_THROW(Client(r.server->port()), boost::system::system_error);
    Client c(r.server->port(), "?token=abc123");
    c.until("state");
    EXPECT_NE(r.server->url().find("?token=abc123"), std::string::npos);
}

TEST(ServeServer, EditSavedIsWhatNerfptRenderRenders) {
    if (!fs::exists(test::cli_binary())) GTEST_SKIP() << "the nerfpt binary is not built";
    const fs::path scene = copy_serve_scene();
    {
        Running r(scene);
        Client c(r.server->port());
        c.until("state");
        // The cube from x = -1 to x = +1, then saved.
        c.send(R"({"type": "volume", "index": 0, "translation": [1, 0, 0]})");
        c.until("state", [](const json& s) { return s["volumes"][0]["translation"][0] == 1.0; });
        c.send(R"({"type": "save"})");
        const json saved = c.until("saved");
        EXPECT_TRUE(saved["notes"].empty()) << saved.dump();
    }
    const fs::path out = scene.parent_path() / "out.exr";
    ASSERT_EQ(test::run_cli({"render", scene.string(), "-o", out.string(), "--spp", "1"},
                            scene.parent_path() / "render.log"),
              0)
        << test::read_text(scene.parent_path() / "render.log");
    const Image image = read_image(out, false);
    // The camera at (0, 0, 5), 40 degrees: the cube's centre at x = +1 (z = 0) is at pixel 80 + 60 * 1 / (5
    // tan 20deg).
    const int x_new = int(80 + 60.0 / (5 * std::tan(20 * 3.14159265358979 / 180)));
    const int x_old = int(80 - 60.0 / (5 * std::tan(20 * 3.14159265358979 / 180)));
    const Rgb at_new = image.rgb(x_new, 60), at_old = image.rgb(x_old, 60);
    EXPECT_NEAR(at_new.x, 1.0f, 0.02f);  // the cube's white emission
    EXPECT_NEAR(at_new.z, 1.0f, 0.02f);
    EXPECT_NEAR(at_old.x, 0.5f, 0.01f);  // the wall where the cube was
    EXPECT_NEAR(at_old.z, 0.125f, 0.01f);
}

}  // namespace
}  // namespace npt::serve
