// A page of `nerfpt serve` for the C++ tests: a Boost.Beast WebSocket client that reads the server's
// messages, JSON text or a frame (4-byte little-endian header length, the JSON header, a JPEG); a frame's pixel;
// the serve test scene in a temporary folder.
#pragma once

#include <gtest/gtest.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <turbojpeg.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "test_support.h"

namespace npt::test {

struct ServeClient {
    boost::asio::io_context ioc;
    boost::beast::websocket::stream<boost::asio::ip::tcp::socket> ws{ioc};
    std::string last_jpeg;  // of the last frame next() returned

    explicit ServeClient(uint16_t port, const std::string& query = {}) {
        boost::asio::ip::tcp::resolver resolver(ioc);
        boost::asio::connect(ws.next_layer(), resolver.resolve("127.0.0.1", std::to_string(port)));
        ws.handshake("127.0.0.1:" + std::to_string(port), "/ws" + query);
    }
    void send(const std::string& text) {
        ws.text(true);
        ws.write(boost::asio::buffer(text));
    }
    // The next message: JSON text, or a frame's header (type "frame") with its JPEG size in "jpeg_bytes".
    nlohmann::json next() {
        boost::beast::flat_buffer b;
        ws.read(b);
        const std::string data = boost::beast::buffers_to_string(b.data());
        if (ws.got_text()) return nlohmann::json::parse(data);
        EXPECT_GE(data.size(), 4u);
        const uint32_t n = uint32_t(uint8_t(data[0])) | uint32_t(uint8_t(data[1])) << 8 |
                           uint32_t(uint8_t(data[2])) << 16 | uint32_t(uint8_t(data[3])) << 24;
        nlohmann::json h = nlohmann::json::parse(data.substr(4, n));
        h["jpeg_bytes"] = data.size() - 4 - n;
        EXPECT_EQ(uint8_t(data[4 + n]), 0xFF);  // JPEG SOI marker
        EXPECT_EQ(uint8_t(data[5 + n]), 0xD8);
        last_jpeg = data.substr(4 + n);
        return h;
    }
    // Messages until one of `type` that satisfies `ok` (at most `limit` messages).
    template <typename Fn>
    nlohmann::json until(const std::string& type, Fn ok, int limit = 5000) {
        for (int i = 0; i < limit; ++i) {
            nlohmann::json m = next();
            if (m["type"] == type && ok(m)) return m;
        }
        ADD_FAILURE() << "no '" << type << "' message";
        return {};
    }
    nlohmann::json until(const std::string& type) {
        return until(type, [](const nlohmann::json&) { return true; });
    }
};

// A frame's pixel (x, y) as 8-bit RGB; a failure and {-1, -1, -1} outside it.
inline std::array<int, 3> jpeg_pixel(const std::string& jpeg, int x, int y) {
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

// The serve test scene (tests/data/serve: a wall and a cube) copied to a temporary folder; its scene.json. From
// the source tree, or from the working tree the GPU machine runs in (scripts/gpu_check.sh runs from its root);
// empty when neither has it.
inline std::filesystem::path copy_serve_scene() {
    namespace fs = std::filesystem;
    fs::path src = test_data() / "serve";
    if (!fs::exists(src)) src = fs::path("tests") / "data" / "serve";
    if (!fs::exists(src)) return {};
    const fs::path dir = temp_dir();
    for (const auto& e : fs::directory_iterator(src)) fs::copy_file(e.path(), dir / e.path().filename());
    return dir / "scene.json";
}

}  // namespace npt::test
