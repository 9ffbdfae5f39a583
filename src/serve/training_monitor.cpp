#include "serve/training_monitor.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/error.h"
#include "core/image_metrics.h"
#include "nerf/eval_images.h"

namespace npt::serve {
namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_between(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// JSON has no infinity or NaN: null stands for them.
json finite_or_null(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// An image of sRGB-encoded values in [0, 1] (NeRF renders, ground truth) as 8-bit RGB rows.
std::vector<uint8_t> to_rgb8(const Image& img) {
    std::vector<uint8_t> rgb(size_t(img.width) * size_t(img.height) * 3);
    for (size_t p = 0, n = size_t(img.width) * size_t(img.height); p < n; ++p)
        for (int c = 0; c < 3; ++c) {
            const float v = img.pixels[p * size_t(img.channels) + size_t(c)];
            rgb[3 * p + size_t(c)] = uint8_t(std::lround(std::clamp(std::isfinite(v) ? v : 0.0f, 0.0f, 1.0f) * 255.0f));
        }
    return rgb;
}

json describe_camera(const nerf::Camera& c) {
    const auto& m = c.camera_to_world.m;
    return {{"position", {m[0][3], m[1][3], m[2][3]}},
            {"forward", {-m[0][2], -m[1][2], -m[2][2]}},
            {"up", {m[0][1], m[1][1], m[2][1]}},
            {"fov_deg", 2.0 * std::atan(0.5 * c.height / c.fy) * 180.0 / 3.14159265358979323846}};
}

// A pinhole camera of width x height from the page's camera (three.js: looks down -Z, +Y up; so do NeRF cameras).
nerf::Camera camera_from_message(const CameraMsg& m, int width, int height) {
    auto cross = [](V3 a, V3 b) {
        return V3{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    };
    auto norm = [](V3 v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); };
    auto scaled = [](V3 v, double s) { return V3{v[0] * s, v[1] * s, v[2] * s}; };
    V3 f = m.forward;
    if (!(norm(f) > 1e-12)) f = {0, 0, -1};
    f = scaled(f, 1.0 / norm(f));
    V3 r = cross(f, m.up);
    if (!(norm(r) > 1e-9)) r = cross(f, std::abs(f[2]) < 0.9 ? V3{0, 0, 1} : V3{1, 0, 0});  // up along forward
    r = scaled(r, 1.0 / norm(r));
    const V3 u = cross(r, f);
    nerf::Camera c;
    for (int i = 0; i < 3; ++i) {
        c.camera_to_world.m[size_t(i)][0] = r[size_t(i)];
        c.camera_to_world.m[size_t(i)][1] = u[size_t(i)];
        c.camera_to_world.m[size_t(i)][2] = -f[size_t(i)];
        c.camera_to_world.m[size_t(i)][3] = m.position[size_t(i)];
    }
    const double fov = std::clamp(m.fov_deg, 1.0, 170.0) * 3.14159265358979323846 / 180.0;
    c.width = width;
    c.height = height;
    c.fy = c.fx = float(0.5 * height / std::tan(0.5 * fov));
    c.cx = 0.5f * float(width);
    c.cy = 0.5f * float(height);
    return c;
}

}  // namespace

std::string base64_encode(const std::string& bytes) {
    static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((bytes.size() + 2) / 3 * 4);
    size_t i = 0;
    for (; i + 2 < bytes.size(); i += 3) {
        const uint32_t v = uint32_t(uint8_t(bytes[i])) << 16 | uint32_t(uint8_t(bytes[i + 1])) << 8 | uint8_t(bytes[i + 2]);
        for (int s = 18; s >= 0; s -= 6) out += k[(v >> s) & 63];
    }
    if (i < bytes.size()) {
        uint32_t v = uint32_t(uint8_t(bytes[i])) << 16;
        if (i + 1 < bytes.size()) v |= uint32_t(uint8_t(bytes[i + 1])) << 8;
        out += k[(v >> 18) & 63];
        out += k[(v >> 12) & 63];
        out += i + 1 < bytes.size() ? k[(v >> 6) & 63] : '=';
        out += '=';
    }
    return out;
}

// The held-out views at the eval size, their ground truth over white.
struct TrainingMonitor::HeldOut {
    nerf::Dataset data;
    std::vector<Image> truth;
    std::string split;  // "test", or "train" when the data set has no held-out views
};

// The model as of one step, without its optimizer state, and the renderer that draws it.
struct TrainingMonitor::Snapshot {
    nerf::NerfModel model;
    uint64_t step = 0;
    double elapsed = 0;
    std::unique_ptr<nerf::ViewRendererBackend> renderer;
};

TrainingMonitor::TrainingMonitor(const TrainingMonitorOptions& options, ViewerSink& sink)
    : m_options(options), m_sink(sink) {
    m_stages = json::array();
    std::lock_guard lock(m_mutex);
    rebuild_state_locked();
}

TrainingMonitor::~TrainingMonitor() { stop(); }

void TrainingMonitor::start() {
    if (!m_thread.joinable()) m_thread = std::thread([this] { run(); });
}

void TrainingMonitor::stop() {
    {
        std::lock_guard lock(m_mutex);
        m_stop = true;
    }
    m_wake.notify_all();
    if (m_thread.joinable()) m_thread.join();
}

double TrainingMonitor::snapshot_seconds_total() const {
    std::lock_guard lock(m_mutex);
    return m_snapshot_seconds;
}

double TrainingMonitor::eval_seconds_total() const {
    std::lock_guard lock(m_mutex);
    return m_eval_seconds;
}

// --- the training thread -----------------------------------------------------------------------------------

void TrainingMonitor::on_start(const nerf::TrainingStart& start) {
    {
        std::lock_guard lock(m_mutex);
        m_start = start;
        m_run = {{"frames", start.data ? start.data->cameras.size() : 0},
                 {"width", start.data ? start.data->width : 0},
                 {"height", start.data ? start.data->height : 0},
                 {"backend", nerf::backend_name(start.backend)},
                 {"device", start.device},
                 {"start_step", start.start_step},
                 {"target_steps", start.target_steps == UINT64_MAX ? json(nullptr) : json(start.target_steps)},
                 {"target_seconds", start.target_seconds}};
        m_phase = "training";
        m_finished = false;
        m_state_dirty = true;
        m_last_step_wall = m_started = Clock::now();
    }
    m_wake.notify_all();
}

void TrainingMonitor::on_step(const nerf::StepStats& stats, double elapsed, double fraction) {
    const auto now = Clock::now();
    const double psnr = nerf::psnr_from_mse(stats.mse);
    std::lock_guard lock(m_mutex);
    const double dt = seconds_between(m_last_step_wall, now);
    m_last_step_wall = now;
    if (dt > 0) m_steps_per_s = m_steps_per_s == 0 ? 1.0 / dt : 0.95 * m_steps_per_s + 0.05 / dt;
    m_step = stats.step;
    m_elapsed = elapsed;
    m_fraction = fraction;
    m_loss = stats.loss;
    m_psnr = psnr;
    m_have_step = true;
    if (stats.seconds > 0 && stats.rays > 0) {
        const double sps = double(stats.marched) / stats.seconds, spr = double(stats.marched) / double(stats.rays);
        m_samples_per_s = m_samples_per_s == 0 ? sps : 0.9 * m_samples_per_s + 0.1 * sps;
        m_samples_per_ray = m_samples_per_ray == 0 ? spr : 0.9 * m_samples_per_ray + 0.1 * spr;
    }
    if (!std::isfinite(stats.loss)) return;
    m_bucket_loss += stats.loss;
    m_bucket_psnr += psnr;
    if (++m_bucket_n < m_stride) return;
    m_hist_step.push_back(double(stats.step));
    m_hist_loss.push_back(m_bucket_loss / double(m_bucket_n));
    m_hist_psnr.push_back(m_bucket_psnr / double(m_bucket_n));
    m_bucket_n = 0;
    m_bucket_loss = m_bucket_psnr = 0;
    if (m_hist_step.size() >= k_max_points) {
        // Halve: each pair of points becomes their mean, and a point now stands for twice the steps.
        const size_t half = m_hist_step.size() / 2;
        for (size_t i = 0; i < half; ++i) {
            m_hist_step[i] = m_hist_step[2 * i + 1];
            m_hist_loss[i] = 0.5 * (m_hist_loss[2 * i] + m_hist_loss[2 * i + 1]);
            m_hist_psnr[i] = 0.5 * (m_hist_psnr[2 * i] + m_hist_psnr[2 * i + 1]);
        }
        m_hist_step.resize(half);
        m_hist_loss.resize(half);
        m_hist_psnr.resize(half);
        m_stride *= 2;
        m_hist_reset = true;
    }
}

bool TrainingMonitor::snapshot_due() {
    if (!m_want_snapshot.load(std::memory_order_relaxed)) return false;
    std::lock_guard lock(m_mutex);
    m_snapshot_asked = Clock::now();  // the caller syncs the model now: timed with the copy
    return true;
}

void TrainingMonitor::on_snapshot(const nerf::NerfModel& model, uint64_t step) {
    auto s = std::make_unique<Snapshot>();
    s->model.config = model.config;
    s->model.aabb_scale = model.aabb_scale;
    s->model.world_to_model = model.world_to_model;
    s->model.params = model.params;
    s->model.occupancy = model.occupancy;
    s->step = step;
    {
        std::lock_guard lock(m_mutex);
        s->elapsed = m_elapsed;
        if (m_want_snapshot.exchange(false))
            m_snapshot_seconds += seconds_between(m_snapshot_asked, Clock::now());
        m_pending = std::move(s);
    }
    m_wake.notify_all();
}

void TrainingMonitor::on_finish(uint64_t steps, double elapsed, bool interrupted) {
    {
        std::lock_guard lock(m_mutex);
        m_step = steps;
        m_elapsed = elapsed;
        m_fraction = 1.0;
        m_finished = true;
        m_interrupted = interrupted;
        m_phase = interrupted ? "training interrupted" : "training finished";
        m_state_dirty = true;
        m_want_snapshot = false;
    }
    m_wake.notify_all();
}

// --- the server's thread -----------------------------------------------------------------------------------

std::shared_ptr<const std::string> TrainingMonitor::state() const {
    std::lock_guard lock(m_mutex);
    return m_state;
}

void TrainingMonitor::post(uint64_t client, ClientMessage message) {
    if (auto* c = std::get_if<CameraMsg>(&message)) {
        {
            std::lock_guard lock(m_mutex);
            m_camera = *c;
        }
        m_wake.notify_all();
        return;
    }
    spdlog::warn("serve: page {}: the training page takes camera messages only", client);
    send(client, {{"type", "error"}, {"message", "the training page takes camera messages only"}});
}

void TrainingMonitor::set_stages(json stages) {
    {
        std::lock_guard lock(m_mutex);
        m_stages = std::move(stages);
        m_state_dirty = true;
    }
    m_wake.notify_all();
}

void TrainingMonitor::set_phase(const std::string& phase) {
    {
        std::lock_guard lock(m_mutex);
        m_phase = phase;
        m_state_dirty = true;
    }
    m_wake.notify_all();
}

// --- the worker ----------------------------------------------------------------------------------------------

void TrainingMonitor::send(uint64_t client, const json& j) {
    m_sink.send_text(client, std::make_shared<const std::string>(j.dump(-1, ' ', false, json::error_handler_t::replace)));
}

void TrainingMonitor::rebuild_state_locked() {
    json st = {{"type", "state"},
               {"mode", "train"},
               {"title", m_options.title},
               {"phase", m_phase},
               {"run", m_run},
               {"stages", m_stages},
               {"finished", m_finished},
               {"interrupted", m_interrupted},
               {"step", m_step},
               {"elapsed", m_elapsed},
               {"history", {{"step", m_hist_step}, {"loss", m_hist_loss}, {"psnr", m_hist_psnr}}},
               {"evals", m_evals},
               {"strip", m_strip_b64}};
    if (m_held) {
        st["held_out"] = {{"split", m_held->split},
                          {"views", m_held->data.cameras.size()},
                          {"width", m_held->data.width},
                          {"height", m_held->data.height},
                          {"camera", describe_camera(m_held->data.cameras[0])}};
        if (m_start) {
            const Vec3 centre = m_start->world_to_model.inverse().transform_point(Vec3(0.5f, 0.5f, 0.5f));
            st["held_out"]["target"] = {centre.x, centre.y, centre.z};
        }
    }
    m_state = std::make_shared<const std::string>(st.dump(-1, ' ', false, json::error_handler_t::replace));
    m_state_dirty = false;
}

void TrainingMonitor::publish_status(bool force) {
    json status;
    bool state_changed = false;
    std::shared_ptr<const std::string> state;
    {
        std::lock_guard lock(m_mutex);
        const auto now = Clock::now();
        if (!force && seconds_between(m_last_status, now) < m_options.status_interval) return;
        m_last_status = now;
        if (!m_have_step && !m_state_dirty && !force) return;
        const uint64_t target = m_start ? m_start->target_steps : 0;
        double remaining = -1;
        if (!m_finished && m_start) {
            if (target != UINT64_MAX && m_steps_per_s > 0 && target > m_step)
                remaining = double(target - m_step) / m_steps_per_s;
            if (m_start->target_seconds > 0) {
                const double r = std::max(0.0, m_start->target_seconds - m_elapsed);
                remaining = remaining < 0 ? r : std::min(remaining, r);
            }
        }
        status = {{"type", "train"},
                  {"step", m_step},
                  {"target_steps", target == UINT64_MAX || target == 0 ? json(nullptr) : json(target)},
                  {"fraction", m_fraction},
                  {"loss", finite_or_null(m_loss)},
                  {"psnr", finite_or_null(m_psnr)},
                  {"steps_per_s", m_finished ? 0.0 : m_steps_per_s},
                  {"elapsed", m_elapsed},
                  {"remaining", remaining >= 0 ? json(remaining) : json(nullptr)},
                  {"phase", m_phase},
                  {"finished", m_finished}};
        const size_t from = m_hist_reset ? 0 : m_hist_sent;
        status["reset"] = m_hist_reset;
        status["points"] = {{"step", std::vector<double>(m_hist_step.begin() + long(from), m_hist_step.end())},
                            {"loss", std::vector<double>(m_hist_loss.begin() + long(from), m_hist_loss.end())},
                            {"psnr", std::vector<double>(m_hist_psnr.begin() + long(from), m_hist_psnr.end())}};
        m_hist_sent = m_hist_step.size();
        m_hist_reset = false;
        m_have_step = false;
        state_changed = m_state_dirty;
        rebuild_state_locked();  // a page that connects now starts from all of it
        state = m_state;
    }
    // A new phase, stage or the held-out views: every page takes the whole state again.
    if (state_changed) m_sink.send_text(0, state);
    send(0, status);
}

void TrainingMonitor::run() {
    for (;;) {
        std::optional<nerf::TrainingStart> start;
        std::unique_ptr<Snapshot> snapshot;
        std::optional<CameraMsg> camera;
        bool finished = false;
        {
            std::unique_lock lock(m_mutex);
            // A pending camera waits for m_orbit_ready: the wait ends then at the latest.
            auto timeout = std::chrono::duration_cast<Clock::duration>(
                std::chrono::duration<double>(m_options.status_interval));
            if (m_camera && m_model) timeout = std::clamp(m_orbit_ready - Clock::now(), Clock::duration(0), timeout);
            m_wake.wait_for(lock, timeout, [&] {
                return m_stop || (m_start && !m_held && !m_held_failed) || m_pending ||
                       (m_camera && m_model && Clock::now() >= m_orbit_ready);
            });
            if (m_stop) return;
            if (m_start && !m_held && !m_held_failed) start = m_start;
            snapshot = std::move(m_pending);
            if ((m_model || snapshot) && Clock::now() >= m_orbit_ready) camera.swap(m_camera);
            finished = m_finished;
        }
        try {
            if (start) {
                load_held_out(*start);
                // Not at once: a model of a few steps, its occupancy grid still full, is the slowest to render.
                m_next_snapshot = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                     std::chrono::duration<double>(m_options.min_eval_interval));
            }
            if (snapshot) {
                snapshot->renderer = nerf::make_view_renderer(m_start->backend, snapshot->model, nerf::ViewPrecision::fp32);
                m_model = std::move(snapshot);
                evaluate();
                if (!camera && m_view_camera) camera = m_view_camera;  // the orbit view shows the new model
            }
            if (camera && m_model) {
                m_view_camera = camera;
                const auto t0 = Clock::now();
                render_orbit();
                const double share = std::clamp(m_options.max_orbit_share, 0.01, 1.0);
                m_orbit_ready = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                   (Clock::now() - t0) * ((1.0 - share) / share));
            }
        } catch (const std::exception& e) {
            spdlog::warn("serve: live training page: {}", e.what());
            send(0, {{"type", "error"}, {"message", e.what()}});
            std::lock_guard lock(m_mutex);
            if (start && !m_held) m_held_failed = true;  // no views to evaluate: do not try again
        }
        if (!finished && m_held && Clock::now() >= m_next_snapshot && !m_want_snapshot && first_eval_affordable())
            m_want_snapshot = true;
        publish_status(false);
    }
}

// Before the first evaluation has been timed: its cost predicted from the training's own rate (a sample of a
// render taken to cost as much as a sample of a training step), and it waits until that is at most
// max_eval_share of the time trained so far. On a GPU this is at once; on 2 CPU cores, a model of a few dozen
// steps (its occupancy grid still nearly full) can take seconds to render.
bool TrainingMonitor::first_eval_affordable() const {
    if (m_evals_done > 0 || !m_held) return true;
    std::lock_guard lock(m_mutex);
    if (m_samples_per_s <= 0) return false;
    const double rays = double(m_held->data.cameras.size()) * m_held->data.width * m_held->data.height;
    const double predicted = rays * m_samples_per_ray / m_samples_per_s;
    return predicted <= m_options.max_eval_share * seconds_between(m_started, Clock::now());
}

void TrainingMonitor::load_held_out(const nerf::TrainingStart& start) {
    auto held = std::make_unique<HeldOut>();
    const size_t n = size_t(std::max(1, m_options.eval_views));
    std::error_code ec;
    const fs::path data(start.data_path);
    if (start.split != "test" && fs::is_directory(data, ec) && fs::exists(data / "transforms_test.json", ec)) {
        held->data = nerf::load_dataset(data, "test", {}, n);
        held->split = "test";
    } else if (start.data && !start.data->cameras.empty()) {
        // No held-out views: a few training views, said so on the page.
        const nerf::Dataset& d = *start.data;
        held->split = "train";
        held->data.width = d.width;
        held->data.height = d.height;
        const size_t m = std::min(n, d.cameras.size());
        for (size_t k = 0; k < m; ++k) {
            const size_t i = k * d.cameras.size() / m;
            held->data.cameras.push_back(d.cameras[i]);
            held->data.names.push_back(d.names.empty() ? std::string() : d.names[i]);
            held->data.rgba.insert(held->data.rgba.end(), d.image(i), d.image(i) + d.image_bytes());
        }
    } else {
        throw Error("no views to evaluate");
    }
    const int side = std::max(held->data.width, held->data.height);
    const int eval_side = m_options.eval_side > 0 ? m_options.eval_side : start.backend == nerf::Backend::cpu ? 64 : 160;
    const int factor = std::max(1, (side + eval_side - 1) / eval_side);
    if (factor > 1) nerf::downscale_dataset(held->data, factor);
    for (size_t i = 0; i < held->data.cameras.size(); ++i)
        held->truth.push_back(nerf::ground_truth_image(held->data, i, Rgb(1.0f)));
    spdlog::debug("serve: {} {} views of {}x{} for the live PSNR", held->data.cameras.size(), held->split,
                  held->data.width, held->data.height);
    std::lock_guard lock(m_mutex);
    m_held = std::move(held);
    m_state_dirty = true;
}

void TrainingMonitor::evaluate() {
    if (!m_held || !m_model) return;
    const auto t0 = Clock::now();
    std::vector<double> psnrs;
    double sum = 0;
    std::string strip_b64;
    nerf::ViewOptions vo;  // white background, as the truth
    for (size_t i = 0; i < m_held->data.cameras.size(); ++i) {
        const Image render = m_model->renderer->render(m_held->data.cameras[i], vo, [this](size_t, size_t) {
            std::lock_guard lock(m_mutex);
            return !m_stop;
        });
        const double p = psnr(m_held->truth[i], render);
        psnrs.push_back(p);
        sum += p;
        if (i == 0) {
            const Image strip = nerf::comparison_strip(m_held->truth[i], render);
            strip_b64 = base64_encode(m_jpeg.encode(to_rgb8(strip), strip.width, strip.height, 90));
        }
    }
    const double seconds = seconds_between(t0, Clock::now());
    const double mean = sum / double(psnrs.size());
    json views = json::array();
    for (double p : psnrs) views.push_back(finite_or_null(p));
    const json e = {{"step", m_model->step},
                    {"elapsed", m_model->elapsed},
                    {"psnr", finite_or_null(mean)},
                    {"views", views},
                    {"eval_ms", seconds * 1e3}};
    double snapshot_seconds = 0;
    {
        std::lock_guard lock(m_mutex);
        m_evals.push_back(e);
        m_strip_b64 = strip_b64;
        m_eval_seconds += seconds;
        snapshot_seconds = m_snapshot_seconds;
        // The next snapshot once this one's cost (copy + renders) is at most max_eval_share of the time since.
        const double cost = seconds + (m_evals.size() > 0 ? snapshot_seconds / double(m_evals.size()) : 0.0);
        m_next_snapshot =
            Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                               std::max(m_options.min_eval_interval, cost / std::max(1e-3, m_options.max_eval_share))));
    }
    ++m_evals_done;
    json msg = e;
    msg["type"] = "eval";
    msg["split"] = m_held->split;
    msg["strip"] = strip_b64;
    msg["strip_width"] = m_held->data.width * 3;
    msg["strip_height"] = m_held->data.height;
    send(0, msg);
    spdlog::debug("serve: held-out PSNR {:.2f} dB at step {} ({:.0f} ms; snapshots so far: {:.0f} ms in all)", mean,
                  m_model->step, seconds * 1e3, snapshot_seconds * 1e3);
}

void TrainingMonitor::render_orbit() {
    const CameraMsg& cm = *m_view_camera;
    const int side = std::max(16, m_options.view_side);
    const double aspect = m_held ? double(m_held->data.width) / double(m_held->data.height) : 1.0;
    const int w = aspect >= 1 ? side : std::max(8, int(std::lround(side * aspect)));
    const int h = aspect >= 1 ? std::max(8, int(std::lround(side / aspect))) : side;
    const nerf::Camera cam = camera_from_message(cm, w, h);
    const auto t0 = Clock::now();
    nerf::ViewOptions vo;
    const Image img = m_model->renderer->render(cam, vo, [this](size_t, size_t) {
        std::lock_guard lock(m_mutex);
        return !m_stop;
    });
    const double ms = seconds_between(t0, Clock::now()) * 1e3;
    const std::string jpeg = m_jpeg.encode(to_rgb8(img), img.width, img.height);
    const json header = {{"type", "frame"},
                         {"view", "orbit"},
                         {"seq", ++m_seq},
                         {"width", img.width},
                         {"height", img.height},
                         {"step", m_model->step},
                         {"render_ms", ms},
                         {"camera", {{"position", cm.position}, {"forward", cm.forward}, {"up", cm.up}, {"fov_deg", cm.fov_deg}}}};
    const std::string h_text = header.dump();
    auto frame = std::make_shared<std::string>(4, '\0');
    const uint32_t n = uint32_t(h_text.size());
    for (int i = 0; i < 4; ++i) (*frame)[size_t(i)] = char((n >> (8 * i)) & 0xff);
    *frame += h_text;
    *frame += jpeg;
    m_sink.broadcast_frame(std::move(frame));
}

}  // namespace npt::serve
