// `--serve` of `nerfpt train` and `nerfpt capture`: the server and the live-training page's monitor
// (src/serve/training_monitor.h) for the length of the command, and the options that ask for them.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <thread>

#include "serve/server.h"
#include "serve/training_monitor.h"

namespace npt::cli {

struct LiveServeArgs {
    bool enabled = false;
    std::string host = "127.0.0.1";
    int port = 7007;
    double eval_every = 10;  // seconds between held-out evaluations, at least
    double eval_share = 0.05;  // their time, at most this share of the training's
};

// --serve, --host, --port on a subcommand.
void add_live_serve_options(CLI::App* cmd, LiveServeArgs& args);

class LiveTraining {
  public:
    // Binds (an npt::Error when the port is taken), starts the server's thread and the monitor, prints the URL.
    LiveTraining(const LiveServeArgs& args, const std::string& title);
    ~LiveTraining();
    LiveTraining(const LiveTraining&) = delete;
    LiveTraining& operator=(const LiveTraining&) = delete;

    serve::TrainingMonitor& monitor() { return *m_monitor; }
    // Says that the work is done and serves the page until Ctrl-C (which ends the process).
    void serve_until_interrupted();

  private:
    std::unique_ptr<serve::Server> m_server;
    std::unique_ptr<serve::TrainingMonitor> m_monitor;
    std::thread m_io;
};

}  // namespace npt::cli
