#include "live_training.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstdio>

namespace npt::cli {

void add_live_serve_options(CLI::App* cmd, LiveServeArgs& args) {
    cmd->add_flag("--serve", args.enabled,
                  "Serve a live-training page while it trains (prints its URL): loss and PSNR over the steps, "
                  "steps/s, time left, PSNR of 3 held-out views (at most every --serve-eval-every seconds, and at most 5% "
                  "of the time: --serve-eval-share), "
                  "truth | render | error of one of them, and the current model orbited from the page. After "
                  "training the page stays up until Ctrl-C");
    cmd->add_option("--host", args.host,
                    "With --serve: address to listen on (default: 127.0.0.1, this machine only); any other address "
                    "requires the printed token");
    cmd->add_option("--port", args.port, "With --serve: TCP port, or 0 for any free one (default: 7007)")
        ->check(CLI::Range(0, 65535));
    cmd->add_option("--serve-eval-every", args.eval_every,
                    "With --serve: seconds between the held-out views' evaluations, at least (default: 10; they "
                    "are spaced further when they would take more than --serve-eval-share of the time)")
        ->check(CLI::Range(0.1, 1e6));
    cmd->add_option("--serve-eval-share", args.eval_share,
                    "With --serve: the largest share of the time the held-out evaluations may take, their cost "
                    "predicted from the training's rate until the first is timed (default: 0.05)")
        ->check(CLI::Range(0.001, 1.0));
}

LiveTraining::LiveTraining(const LiveServeArgs& args, const std::string& title) {
    serve::ServerOptions so;
    so.host = args.host;
    so.port = uint16_t(args.port);
    so.index = "/train.html";
    if (!serve::is_loopback_host(args.host)) so.token = serve::random_token();
    m_server = std::make_unique<serve::Server>(so);
    serve::TrainingMonitorOptions mo;
    mo.title = title;
    mo.min_eval_interval = args.eval_every;
    mo.max_eval_share = args.eval_share;
    m_monitor = std::make_unique<serve::TrainingMonitor>(mo, *m_server);
    m_server->attach(m_monitor.get());
    m_monitor->start();
    m_io = std::thread([this] { m_server->run(); });
    if (!so.token.empty())
        spdlog::warn("listening on {}: anyone who can reach it and has the token can watch the training", args.host);
    fmt::print("nerfpt: live training page at {}\n", m_server->url());
    std::fflush(stdout);
}

LiveTraining::~LiveTraining() {
    m_monitor->stop();
    m_server->stop();
    if (m_io.joinable()) m_io.join();
}

void LiveTraining::serve_until_interrupted() {
    fmt::print("nerfpt: done; the page at {} stays up until Ctrl-C\n", m_server->url());
    std::fflush(stdout);
    if (m_io.joinable()) m_io.join();  // the server runs until the process is interrupted
}

}  // namespace npt::cli
