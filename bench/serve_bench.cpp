// The viewer's interactive numbers (issue 27): a page of a running `nerfpt serve` that moves the camera and times
// what comes back. The camera pans (yaw swinging +-12 degrees about the scene camera's up, position fixed), and a
// new camera message goes out as soon as the frame of the previous one has arrived: what a drag looks like when
// the page is never the bottleneck. Prints a table of
//   - frames/s while moving: camera frames (the first frame after each camera message) per second of wall time;
//   - latency at the server: the frame header's `latency_ms` (camera message received -> frame handed to the
//     socket), and the round trip at this page (message written -> frame read);
//   - pass_ms (the render pass alone), then what the server spends on the frame after it (accumulate, tone map,
//     JPEG encode: the header's *_ms), and the JPEG's size.
// Usage: serve_bench PORT [--seconds S] [--preview N] [--host H]. Start the server first, e.g.
//   nerfpt serve scene.gltf --backend optix --res 1280x720 --port 7123 &   (bench/serve_gpu.sh does it all)
#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;
namespace websocket = boost::beast::websocket;

double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

struct Page {
    boost::asio::io_context ioc;
    websocket::stream<boost::asio::ip::tcp::socket> ws{ioc};
    size_t jpeg_bytes = 0;  // of the last frame read

    Page(const std::string& host, const std::string& port) {
        boost::asio::ip::tcp::resolver resolver(ioc);
        boost::asio::connect(ws.next_layer(), resolver.resolve(host, port));
        ws.next_layer().set_option(boost::asio::ip::tcp::no_delay(true));  // as a browser sends: at once
        ws.read_message_max(64u << 20);
        ws.handshake(host + ":" + port, "/ws");
    }
    void send(const json& j) {
        ws.text(true);
        ws.write(boost::asio::buffer(j.dump()));
    }
    // The next message: JSON text, or a frame's JSON header (4-byte little-endian length, header, JPEG).
    json next() {
        boost::beast::flat_buffer b;
        ws.read(b);
        const std::string data = boost::beast::buffers_to_string(b.data());
        if (ws.got_text()) return json::parse(data);
        if (data.size() < 4) throw std::runtime_error("a binary message shorter than its length field");
        const uint32_t n = uint32_t(uint8_t(data[0])) | uint32_t(uint8_t(data[1])) << 8 |
                           uint32_t(uint8_t(data[2])) << 16 | uint32_t(uint8_t(data[3])) << 24;
        if (data.size() < 4 + size_t(n)) throw std::runtime_error("a frame shorter than its header length");
        jpeg_bytes = data.size() - 4 - n;
        return json::parse(data.substr(4, n));
    }
};

struct Vec {
    double x, y, z;
};
Vec operator*(Vec a, double s) { return {a.x * s, a.y * s, a.z * s}; }
Vec operator+(Vec a, Vec b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
double dot(Vec a, Vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec cross(Vec a, Vec b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
Vec vec(const json& j) { return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; }

// v rotated by `angle` radians about the unit axis k (Rodrigues).
Vec rotate(Vec v, Vec k, double angle) {
    const double c = std::cos(angle), s = std::sin(angle);
    return v * c + cross(k, v) * s + k * (dot(k, v) * (1 - c));
}

double percentile(std::vector<double> v, double q) {
    if (v.empty()) return NAN;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, size_t(q * double(v.size() - 1) + 0.5))];
}

int usage(const char* why) {
    std::fprintf(stderr, "serve_bench: %s\nusage: serve_bench PORT [--seconds S] [--preview N] [--host H]\n", why);
    return 2;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) return usage("no PORT");
    std::string port = argv[1], host = "127.0.0.1";
    double seconds = 10;
    int preview = 0;  // 0: the server's own preview divisor
    for (int i = 2; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) return usage(("no value after " + a).c_str());
        if (a == "--seconds") seconds = std::atof(argv[++i]);
        else if (a == "--preview") preview = std::atoi(argv[++i]);
        else if (a == "--host") host = argv[++i];
        else return usage(("unknown option " + a).c_str());
    }
    if (!(seconds > 0 && seconds <= 3600)) return usage("--seconds must be in (0, 3600]");
    try {
        Page page(host, port);
        json state;
        do state = page.next();
        while (state.value("type", "") != "state");
        if (preview > 0) page.send({{"type", "settings"}, {"preview_divisor", preview}});
        const Vec position = vec(state["camera"]["position"]), forward = vec(state["camera"]["forward"]),
                  up = vec(state["camera"]["up"]);
        std::printf("server: %s backend, %dx%d, preview divisor %d; %s\n", state.value("backend", "?").c_str(),
                    state.value("width", 0), state.value("height", 0),
                    preview > 0 ? preview : state.value("preview_divisor", 0), state.value("scene", "").c_str());

        std::vector<double> latency, round_trip, pass, accumulate, tonemap, encode, bytes;
        int width = 0, height = 0;
        // The clock starts at the first move's frame: before it OptiX may still be compiling its modules (up to a
        // minute on a fresh machine).
        Clock::time_point start;
        bool started = false;
        const double warmup_ms = 2000, end_ms = warmup_ms + seconds * 1e3;
        double measured_ms = 0;
        for (int move = 0;; ++move) {
            const double t = started ? ms_since(start) : 0.0;
            if (t >= end_ms) break;
            // +-12 degrees over a 4-second swing: a slow drag.
            const double yaw = 0.21 * std::sin(2 * M_PI * t / 4000.0);
            const Vec f = rotate(forward, up, yaw);
            page.send({{"type", "camera"},
                       {"position", {position.x, position.y, position.z}},
                       {"forward", {f.x, f.y, f.z}},
                       {"up", {up.x, up.y, up.z}}});
            const auto sent = Clock::now();
            json frame;
            for (;;) {  // frames of the previous camera may still be on their way
                frame = page.next();
                if (frame.value("type", "") == "frame" && frame.contains("latency_ms")) break;
            }
            if (!started) {
                started = true;
                start = Clock::now();
            }
            if (t < warmup_ms) continue;  // start-up: first allocations, caches
            round_trip.push_back(ms_since(sent));
            latency.push_back(frame["latency_ms"].get<double>());
            pass.push_back(frame.value("pass_ms", 0.0));
            accumulate.push_back(frame.value("accumulate_ms", 0.0));
            tonemap.push_back(frame.value("tonemap_ms", 0.0));
            encode.push_back(frame.value("encode_ms", 0.0));
            bytes.push_back(double(page.jpeg_bytes));
            width = frame.value("width", 0);
            height = frame.value("height", 0);
            measured_ms = ms_since(start) - warmup_ms;
        }
        page.ws.close(websocket::close_code::normal);
        if (latency.empty()) throw std::runtime_error("no camera frame arrived after the warm-up");
        const double fps = double(latency.size()) / (measured_ms / 1e3);
        std::printf("%zu camera frames of %dx%d in %.1f s (after a %.0f s warm-up)\n", latency.size(), width, height,
                    measured_ms / 1e3, warmup_ms / 1e3);
        std::printf("| measure | median | p90 | max |\n|---|---|---|---|\n");
        const auto row = [](const char* name, const std::vector<double>& v, const char* unit) {
            std::printf("| %s | %.1f %s | %.1f %s | %.1f %s |\n", name, percentile(v, 0.5), unit, percentile(v, 0.9),
                        unit, percentile(v, 1.0), unit);
        };
        row("server latency (camera message -> frame sent)", latency, "ms");
        row("round trip at the page (sent -> frame read)", round_trip, "ms");
        row("render pass (its download included)", pass, "ms");
        row("accumulate", accumulate, "ms");
        row("tone map", tonemap, "ms");
        row("JPEG encode", encode, "ms");
        std::vector<double> kib;
        for (double b : bytes) kib.push_back(b / 1024);
        row("JPEG", kib, "KiB");
        std::printf("frames/s while moving: %.1f\n", fps);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "serve_bench: %s:%s: %s\n", host.c_str(), port.c_str(), e.what());
        return 1;
    }
    return 0;
}
