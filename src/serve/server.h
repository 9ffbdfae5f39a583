// The viewer's HTTP + WebSocket server (Boost.Beast on one asio thread): serves the page's embedded assets
// and one WebSocket per page, whose text messages go to the Viewer and whose frames come back from it. Only
// server.cpp includes Beast; this header does not, so the CLI does not compile it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "serve/page_io.h"

namespace npt::serve {

struct ServerOptions {
    std::string host = "127.0.0.1";
    uint16_t port = 7007;  // 0: any free port (tests)
    // Required of every request when not empty: "?token=..." on the page's URL (then a cookie) and on the
    // socket.
    std::string token;
    // The page "/" serves: the scene viewer, or "/train.html" (the live-training page).
    std::string index = "/index.html";
    // Paths answered beside the embedded assets (a capture's report and files), or null. Not owned.
    const RouteSource* routes = nullptr;
};

// A random 128-bit token in hex, from the system's random source.
std::string random_token();

// True for 127.0.0.0/8, ::1 and "localhost".
bool is_loopback_host(const std::string& host);

class Server final : public ViewerSink {
  public:
    // Binds host:port (throws npt::Error naming them when that fails: in use, not an address of this
    // machine).
    explicit Server(const ServerOptions& options);
    ~Server() override;
    Server(const Server&) = delete;
    Server& operator=(const Server&) = delete;

    // What the sockets' messages go to (a Viewer or a TrainingMonitor); set before run().
    void attach(PageHandler* handler);
    uint16_t port() const;
    // The page's URL (with the token when there is one).
    std::string url() const;
    // Serves until stop(); on the calling thread.
    void run();
    // From any thread.
    void stop();
    // Open WebSocket sessions (tests: a closed tab frees its session).
    size_t sessions() const;

    void broadcast_frame(std::shared_ptr<const std::string> frame) override;
    void send_frame(uint64_t client, std::shared_ptr<const std::string> frame) override;
    void send_text(uint64_t client, std::shared_ptr<const std::string> text) override;

  private:
    struct Impl;
    std::unique_ptr<Impl> m;
};

}  // namespace npt::serve
