// The live-training page's worker (`nerfpt train --serve`, `nerfpt capture --serve`): a TrainingObserver that
// records loss and PSNR after each step, takes a copy of the model every few seconds, and on its own thread
// renders a few held-out views from that copy (their PSNR, and truth | render | error of the first as a JPEG),
// renders the copy from the camera a page sends (orbit), and sends the page its status twice a second.
// The training thread only takes a lock and copies numbers; a snapshot's copy is timed, and snapshots are spaced
// so that they and the renders cost at most a small share of the training time (max_eval_share).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "nerf/training_observer.h"
#include "serve/frame_encoder.h"
#include "serve/page_io.h"

namespace npt::serve {

struct TrainingMonitorOptions {
    std::string title = "nerfpt train";  // the page's heading
    int eval_views = 3;                  // held-out views whose PSNR is measured
    int eval_side = 0;                   // longest side of the held-out renders, pixels; 0: 64 on the CPU, 160 on a GPU
    int view_side = 192;                 // longest side of the orbit render, pixels
    double min_eval_interval = 10;       // seconds between snapshots, at least
    double max_eval_share = 0.05;        // snapshot + held-out renders, at most this share of the wall time
    // Orbit renders (a page dragging the current-model view) at most this share of the wall time: each waits
    // until the one before has been followed by (1 - share) / share times its own duration, so that a drag
    // on 2 CPU cores cannot take the trainer's cores.
    double max_orbit_share = 0.25;
    double status_interval = 0.5;        // seconds between status messages
};

class TrainingMonitor final : public nerf::TrainingObserver, public PageHandler {
  public:
    TrainingMonitor(const TrainingMonitorOptions& options, ViewerSink& sink);
    ~TrainingMonitor() override;
    TrainingMonitor(const TrainingMonitor&) = delete;
    TrainingMonitor& operator=(const TrainingMonitor&) = delete;

    void start();
    void stop();

    // nerf::TrainingObserver (the training thread)
    void on_start(const nerf::TrainingStart& start) override;
    void on_step(const nerf::StepStats& stats, double elapsed, double fraction) override;
    bool snapshot_due() override;
    void on_snapshot(const nerf::NerfModel& model, uint64_t step) override;
    void on_finish(uint64_t steps, double elapsed, bool interrupted) override;

    // PageHandler (the server's thread)
    std::shared_ptr<const std::string> state() const override;
    void post(uint64_t client, ClientMessage message) override;

    // `nerfpt capture`: its stages, [{"name", "state": "done"|"running"|"pending"|"skipped", "seconds"}].
    void set_stages(nlohmann::json stages);
    // A line for the page's heading ("training", "curate: choosing frames", "finished").
    void set_phase(const std::string& phase);

    // Tests and benchmarks.
    uint64_t evals_done() const { return m_evals_done; }
    double snapshot_seconds_total() const;
    double eval_seconds_total() const;

    static constexpr size_t k_max_points = 2048;  // the loss/PSNR history halves its resolution beyond this

  private:
    struct HeldOut;
    struct Snapshot;

    void run();
    void load_held_out(const nerf::TrainingStart& start);
    bool first_eval_affordable() const;
    void evaluate();
    void render_orbit();
    void publish_status(bool force);
    void rebuild_state_locked();
    void send(uint64_t client, const nlohmann::json& j);

    TrainingMonitorOptions m_options;
    ViewerSink& m_sink;

    mutable std::mutex m_mutex;  // everything below up to the worker's own state
    std::condition_variable m_wake;
    bool m_stop = false;
    std::optional<nerf::TrainingStart> m_start;  // set by on_start; the worker loads the held-out views
    nlohmann::json m_run;                        // what is trained: frames, size, backend, targets
    // Training status, written by on_step.
    uint64_t m_step = 0;
    double m_elapsed = 0, m_fraction = 0, m_loss = 0, m_psnr = 0, m_steps_per_s = 0;
    // The training's field samples per second and per ray: what a held-out render of a model this far is expected
    // to cost before the first one has been timed.
    double m_samples_per_s = 0, m_samples_per_ray = 0;
    std::chrono::steady_clock::time_point m_started{};
    std::chrono::steady_clock::time_point m_last_step_wall{};
    bool m_have_step = false;
    // History: each point the mean over `m_stride` steps.
    std::vector<double> m_hist_step, m_hist_loss, m_hist_psnr;
    uint64_t m_stride = 1, m_bucket_n = 0;
    double m_bucket_loss = 0, m_bucket_psnr = 0;
    size_t m_hist_sent = 0;     // points already sent to the pages
    bool m_hist_reset = false;  // the history was decimated: send it whole
    nlohmann::json m_evals = nlohmann::json::array();  // [{step, elapsed, psnr, views}]
    std::string m_strip_b64;                           // latest truth | render | error, JPEG in base64
    nlohmann::json m_stages;
    std::string m_phase = "starting";
    bool m_finished = false, m_interrupted = false;
    std::shared_ptr<const std::string> m_state;
    bool m_state_dirty = true;
    // Snapshots.
    std::atomic<bool> m_want_snapshot{false};
    std::chrono::steady_clock::time_point m_snapshot_asked{};
    std::unique_ptr<Snapshot> m_pending;  // taken by the worker
    double m_snapshot_seconds = 0, m_eval_seconds = 0;
    std::optional<CameraMsg> m_camera;  // the newest camera a page sent, not yet rendered
    std::atomic<uint64_t> m_evals_done{0};

    // The worker's own state.
    std::unique_ptr<HeldOut> m_held;
    bool m_held_failed = false;
    std::unique_ptr<Snapshot> m_model;
    std::optional<CameraMsg> m_view_camera;  // the camera of the last orbit render
    std::chrono::steady_clock::time_point m_next_snapshot{};
    std::chrono::steady_clock::time_point m_orbit_ready{};  // the next orbit render not before (max_orbit_share)
    std::chrono::steady_clock::time_point m_last_status{};
    uint64_t m_seq = 0;
    JpegEncoder m_jpeg;
    std::thread m_thread;
};

// RFC 4648 base64 (the strip's JPEG inside a JSON message).
std::string base64_encode(const std::string& bytes);

}  // namespace npt::serve
