// A page of `nerfpt serve` for the C++ tests: a Boost.Beast WebSocket client that reads the server's
// messages, JSON text or a frame (4-byte little-endian header length, the JSON header, a JPEG).
#pragma once

#include <gtest/gtest.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

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

}  // namespace npt::test
