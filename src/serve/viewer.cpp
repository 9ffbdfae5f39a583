#include "serve/viewer.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/temp_file.h"
#include "render/scene_data.h"
#include "serve/scene_edits.h"

namespace npt::serve {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// Longer than the gap between a dragging page's camera messages (about 16 ms at 60 Hz) plus the network.
constexpr auto k_gpu_refine_hold = std::chrono::milliseconds(30);

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// The camera a CameraView describes (the default view of a scene without cameras).
scene::Camera camera_from_view(const render::CameraView& v) {
    scene::Camera c;
    c.name = "viewer";
    c.position = v.position;
    c.right = v.right;
    c.up = v.up;
    c.forward = v.forward;
    c.yfov = 2.0f * std::atan(v.tan_half_fov_y);
    return c;
}

}  // namespace

Viewer::Viewer(const ViewerOptions& options, ViewerSink& sink)
    : m_options(options),
      m_sink(sink),
      m_scene(std::make_unique<scene::Scene>(scene::load_scene(options.scene))),
      m_saver(options.scene) {
    scene::Scene& s = *m_scene;
    render::RenderOptions o;
    o.width = options.width;
    o.height = options.height;
    o.backend = options.backend;
    const render::RenderOptions resolved = render::resolve_options(s, o);
    m_width = resolved.width;
    m_height = resolved.height;
    m_target_spp = options.target_spp > 0 ? options.target_spp : resolved.spp;
    m_max_depth = resolved.max_depth;
    m_seed = s.settings.seed;
    m_divisor = options.preview_divisor > 0 ? options.preview_divisor : (options.backend == "cpu" ? 4 : 1);
    // The viewer's own camera, appended after the file's: the one rendered, set to a page's camera before
    // rendering for that page.
    m_file_cameras = s.cameras.size();
    m_start_camera = camera_from_view(render::make_camera_view(s, m_width, m_height));
    s.cameras.push_back(m_start_camera);
    s.camera = int(s.cameras.size()) - 1;
    m_volume_edited.assign(s.volumes.size(), false);
    for (const scene::PunctualLight& l : s.lights) m_light_base.push_back(l.intensity);
    m_light_scale.assign(s.lights.size(), 1.0);
    prepare();
    publish_state();
}

Viewer::~Viewer() { stop(); }

void Viewer::start() {
    if (!m_thread.joinable()) m_thread = std::thread([this] { run(); });
}

void Viewer::stop() {
    {
        std::lock_guard lock(m_mutex);
        m_stop = true;
        m_interrupt = true;
    }
    m_wake.notify_all();
    if (m_thread.joinable()) m_thread.join();
}

void Viewer::post(uint64_t client, ClientMessage message) {
    {
        std::lock_guard lock(m_mutex);
        if (m_queue.size() >= k_max_queue) {
            // A page that sends faster than the worker reads: its oldest camera move is superseded anyway.
            auto oldest_move = m_queue.end();
            for (auto it = m_queue.begin(); it != m_queue.end(); ++it)
                if (std::holds_alternative<CameraMsg>(it->message) &&
                    (oldest_move == m_queue.end() || it->client == client)) {
                    oldest_move = it;
                    if (it->client == client) break;
                }
            if (oldest_move != m_queue.end()) m_queue.erase(oldest_move);
            if (m_queue.size() >= k_max_queue) {
                spdlog::warn("serve: client {}: message queue full, message dropped", client);
                return;
            }
        }
        m_queue.push_back({client, std::move(message), Clock::now()});
        m_interrupt = true;
    }
    m_wake.notify_all();
}

void Viewer::page_opened(uint64_t client) {
    {
        std::lock_guard lock(m_mutex);
        m_opened.push_back(client);
    }
    m_wake.notify_all();
}

void Viewer::page_closed(uint64_t client) {
    {
        std::lock_guard lock(m_mutex);
        m_closed.push_back(client);
        m_interrupt = true;  // a CPU pass for a closed page is not worth finishing
    }
    m_wake.notify_all();
}

std::shared_ptr<const std::string> Viewer::state() const {
    std::lock_guard lock(m_mutex);
    return m_state;
}

render::RenderOptions Viewer::options_for(int width, int height, int spp) const {
    render::RenderOptions r;
    r.width = width;
    r.height = height;
    r.spp = spp;
    r.max_depth = m_max_depth;
    r.seed = m_seed;
    r.threads = m_options.threads;
    r.backend = m_options.backend;
    r.transparent = m_scene->settings.transparent;
    return r;
}

void Viewer::prepare() {
    m_aimed_at = k_nobody;  // the new renderers hold the scene's viewer camera as it is
    m_full.reset();
    m_preview.reset();
    m_full = render::prepare_renderer(*m_scene, options_for(m_width, m_height, 1));
    if (m_divisor > 1)
        m_preview = render::prepare_renderer(
            *m_scene, options_for(std::max(1, m_width / m_divisor), std::max(1, m_height / m_divisor), 1));
}

void Viewer::apply_pose_change(bool camera, bool lights, bool volumes) {
    scene::PoseChanges c;
    c.cameras = camera;
    c.lights = lights;
    c.volumes = volumes;
    m_full->update(c);
    if (m_preview) m_preview->update(c);
}

Viewer::PageView& Viewer::page(uint64_t client) {
    auto [it, made] = m_pages.try_emplace(client);
    if (made) it->second.camera = m_start_camera;
    return it->second;
}

bool Viewer::has_work(Clock::time_point now, Clock::time_point* wake_at) const {
    bool waiting = false;
    for (const auto& [id, v] : m_pages) {
        if (v.dirty) return true;
        if (v.film.passes() >= m_target_spp) continue;
        if (now >= v.refine_after) return true;
        if (!waiting || v.refine_after < *wake_at) *wake_at = v.refine_after;
        waiting = true;
    }
    if (!waiting) *wake_at = Clock::time_point::max();
    return false;
}

Viewer::PageView* Viewer::next_page(uint64_t* client) {
    if (m_pages.empty()) return nullptr;
    // In turn from the page after the last one rendered for: previews first, then passes.
    const auto now = Clock::now();
    auto start = m_pages.upper_bound(m_last_rendered);
    for (int want_preview = 1; want_preview >= 0; --want_preview) {
        auto it = start;
        for (size_t n = 0; n < m_pages.size(); ++n, ++it) {
            if (it == m_pages.end()) it = m_pages.begin();
            PageView& v = it->second;
            const bool needs = want_preview ? v.dirty
                                            : v.film.passes() < m_target_spp && now >= v.refine_after;
            if (needs) {
                *client = it->first;
                return &v;
            }
        }
    }
    return nullptr;
}

void Viewer::aim_at(uint64_t client) {
    if (m_aimed_at == client) return;
    m_scene->cameras.back() = page(client).camera;
    apply_pose_change(true, false, false);
    m_aimed_at = client;
}

void Viewer::run() {
    bool failed = false;  // a render failed: wait for the next change instead of failing again at once
    for (;;) {
        std::deque<Pending> batch;
        std::vector<uint64_t> opened, closed;
        {
            std::unique_lock lock(m_mutex);
            for (;;) {
                if (m_stop || !m_queue.empty() || !m_opened.empty() || !m_closed.empty()) break;
                if (failed) {
                    m_wake.wait(lock);
                    continue;
                }
                Clock::time_point wake_at;
                if (has_work(Clock::now(), &wake_at)) break;
                if (wake_at == Clock::time_point::max())
                    m_wake.wait(lock);
                else
                    m_wake.wait_until(lock, wake_at);
            }
            if (m_stop) return;
            batch.swap(m_queue);
            opened.swap(m_opened);
            closed.swap(m_closed);
            m_interrupt = false;
        }
        for (uint64_t id : opened) page(id);
        for (const Pending& p : batch) {
            try {
                const Restart r = handle(p);
                if (r == Restart::none) continue;
                for (auto& [id, v] : m_pages) {
                    if (r == Restart::page && id != p.client) continue;
                    if (!v.latency_pending) v.change_received = p.received;
                    v.latency_pending = true;
                    v.dirty = true;
                }
                failed = false;
            } catch (const Error& e) {
                spdlog::warn("serve: client {}: {}", p.client, e.what());
                reply(p.client, "error", {{"message", e.what()}});
            }
        }
        for (uint64_t id : closed) {
            m_pages.erase(id);  // its film's memory with it
            if (m_aimed_at == id) m_aimed_at = k_nobody;
        }
        if (failed) continue;
        uint64_t id = 0;
        PageView* v = next_page(&id);
        if (!v) continue;
        m_last_rendered = id;
        try {
            aim_at(id);
            if (v->dirty) {
                v->dirty = false;
                render_preview(id, *v);
                if (m_options.backend != "cpu") v->refine_after = Clock::now() + k_gpu_refine_hold;
            } else {
                render_pass(id, *v);
            }
        } catch (const Cancelled&) {
            // a message arrived: handled at the top of the loop
        } catch (const std::exception& e) {
            spdlog::error("serve: render failed: {}", e.what());
            reply(0, "error", {{"message", std::string("render failed: ") + e.what()}});
            failed = true;
        }
    }
}

Viewer::Restart Viewer::handle(const Pending& p) {
    scene::Scene& s = *m_scene;
    return std::visit(
        [&](const auto& m) -> Restart {
            using T = std::decay_t<decltype(m)>;
            if constexpr (std::is_same_v<T, CameraMsg>) {
                PageView& v = page(p.client);
                v.camera = camera_from_message(m);
                v.camera_from = p.client;
                if (m_aimed_at == p.client) m_aimed_at = k_nobody;
                return Restart::page;
            } else if constexpr (std::is_same_v<T, UseCameraMsg>) {
                if (size_t(m.index) >= m_file_cameras)
                    throw Error("use_camera.index: " + std::to_string(m.index) +
                                " is not a scene camera (the scene has " + std::to_string(m_file_cameras) +
                                ")");
                PageView& v = page(p.client);
                v.camera = s.cameras[size_t(m.index)];
                v.camera.name = "viewer";
                v.camera_from = 0;  // the page moves its controls to it
                if (m_aimed_at == p.client) m_aimed_at = k_nobody;
                return Restart::page;
            } else if constexpr (std::is_same_v<T, VolumeMsg>) {
                if (size_t(m.index) >= s.volumes.size())
                    throw Error("volume.index: " + std::to_string(m.index) +
                                " is out of range (the scene has " + std::to_string(s.volumes.size()) +
                                " volumes)");
                scene::VolumeInstance& v = s.volumes[size_t(m.index)];
                bool placed = false;
                if (m.translation || m.rotation || m.scale) {
                    Trs t = decompose(v.local_to_world);
                    if (m.translation) t.translation = *m.translation;
                    if (m.rotation) t.rotation = *m.rotation;
                    if (m.scale) t.scale = *m.scale;
                    place_volume(v, t);
                    placed = true;
                }
                const std::string old_extras = v.extras_json;
                bool filled = false;
                if (edit_volume_fill(v, m)) {
                    try {
                        prepare();  // a new fill is read where the volume is loaded
                    } catch (const Error&) {
                        v.extras_json = old_extras;
                        prepare();
                        throw;
                    }
                    filled = true;
                }
                if (placed && !filled) apply_pose_change(false, false, true);
                if (placed || filled) {
                    m_volume_edited[size_t(m.index)] = true;
                    publish_state();
                }
                return (placed || filled) ? Restart::all : Restart::none;
            } else if constexpr (std::is_same_v<T, LightMsg>) {
                if (size_t(m.index) >= s.lights.size())
                    throw Error("light.index: " + std::to_string(m.index) +
                                " is out of range (the scene has " + std::to_string(s.lights.size()) +
                                " punctual lights)");
                m_light_scale[size_t(m.index)] = m.intensity_scale;
                s.lights[size_t(m.index)].intensity =
                    m_light_base[size_t(m.index)] * float(m.intensity_scale);
                apply_pose_change(false, true, false);
                publish_state();
                return Restart::all;
            } else if constexpr (std::is_same_v<T, SettingsMsg>) {
                bool restart = false;
                if (m.spp) {
                    m_target_spp = *m.spp;
                    m_spp_edited = true;
                }
                if (m.max_depth && *m.max_depth != m_max_depth) {
                    m_max_depth = *m.max_depth;
                    m_depth_edited = true;
                    restart = true;
                }
                if (m.preview_divisor && *m.preview_divisor != m_divisor) {
                    m_divisor = *m.preview_divisor;
                    m_preview.reset();
                    if (m_divisor > 1)
                        m_preview =
                            render::prepare_renderer(s, options_for(std::max(1, m_width / m_divisor),
                                                                    std::max(1, m_height / m_divisor), 1));
                }
                if (m.view) {
                    const ViewLayer v = *parse_view_layer(*m.view);  // checked by the parser
                    restart |= v != m_view;
                    m_view = v;
                }
                if (m.exposure) {
                    m_exposure = *m.exposure;
                    if (!restart)
                        for (auto& [id, v] : m_pages)
                            if (v.film.passes() > 0) send_frame(id, v, v.film, false, 0, 0);
                }
                publish_state();
                return restart ? Restart::all : Restart::none;
            } else if constexpr (std::is_same_v<T, SaveMsg>) {
                save(p.client);
                return Restart::none;
            } else if constexpr (std::is_same_v<T, RenderStillMsg>) {
                render_still(p.client, m.spp);
                return Restart::none;
            } else if constexpr (std::is_same_v<T, KeyframeAddMsg>) {
                if (m_keyframes.size() >= size_t(k_max_keyframes))
                    throw Error("keyframe_add: the path has " + std::to_string(k_max_keyframes) +
                                " keyframes already");
                m_keyframes.push_back(page(p.client).camera);
                publish_state();
                return Restart::none;
            } else if constexpr (std::is_same_v<T, KeyframesClearMsg>) {
                m_keyframes.clear();
                publish_state();
                return Restart::none;
            } else if constexpr (std::is_same_v<T, KeyframesSaveMsg>) {
                save_keyframes(p.client, m.seconds_per_key);
                return Restart::none;
            }
        },
        p.message);
}

void Viewer::render_preview(uint64_t client, PageView& v) {
    v.film.reset(m_width, m_height);
    v.depth_range = 0.0f;  // the depth view's scale is taken again from the next pass
    if (!m_preview) {
        render_pass(client, v);
        return;
    }
    const render::RenderOptions o =
        options_for(std::max(1, m_width / m_divisor), std::max(1, m_height / m_divisor), 1);
    const auto t0 = Clock::now();
    Accumulator preview;
    preview.reset(o.width, o.height);
    Image layer;
    const Image* pass = &layer;
    if (m_view == ViewLayer::beauty)
        pass = &m_preview->render_frame(o);  // the renderer's own image: not copied
    else
        layer = render_view(*m_preview, o, false, v.depth_range);
    const double seconds = seconds_since(t0);
    const auto t1 = Clock::now();
    preview.add(*pass);
    send_frame(client, v, preview, true, seconds, double(o.width) * o.height, seconds_since(t1));
}

void Viewer::render_pass(uint64_t client, PageView& v) {
    render::RenderOptions o = options_for(m_width, m_height, 1);
    o.seed = m_seed + uint64_t(v.film.passes());
    const auto t0 = Clock::now();
    const bool cpu = m_options.backend == "cpu";
    Image cpu_or_layer;
    const Image* pass = &cpu_or_layer;
    if (m_view == ViewLayer::beauty && !cpu)
        pass = &m_full->render_frame(o);  // the renderer's own image: not copied
    else
        cpu_or_layer = render_view(*m_full, o, cpu, v.depth_range);
    const double seconds = seconds_since(t0);
    const auto t1 = Clock::now();
    v.film.add(*pass);
    const double accumulate = seconds_since(t1);
    // At most ~30 frames a second: a GPU pass takes milliseconds and the page cannot show more.
    if (v.film.passes() == 1 || v.film.passes() >= m_target_spp || seconds_since(v.last_send) >= 1.0 / 30)
        send_frame(client, v, v.film, false, seconds, double(m_width) * m_height, accumulate);
}

Image Viewer::render_view(render::SceneRenderer& renderer, const render::RenderOptions& options,
                          bool cancellable, float& depth_range) {
    render::ProgressFn progress;
    if (cancellable)  // a message arriving mid-pass stops it at the next tile
        progress = [this](uint64_t, uint64_t) {
            if (m_interrupt.load(std::memory_order_relaxed)) throw Cancelled{};
        };
    if (m_view == ViewLayer::beauty) return renderer.render(options, progress);
    render::AovImages aovs;
    const Image rendered = renderer.render(view_options(options, m_view), progress, nullptr, &aovs);
    if (m_view == ViewLayer::depth && !(depth_range > 0.0f)) {
        // Black a tenth beyond the farthest thing the first pass of this view saw; kept while it accumulates.
        float far = 0.0f;
        for (float d : aovs.depth.pixels)
            if (std::isfinite(d)) far = std::max(far, d);
        depth_range = far > 0.0f ? 1.1f * far : 1.0f;
    }
    return view_image(m_view, rendered, aovs, depth_range);
}

void Viewer::send_frame(uint64_t client, PageView& v, const Accumulator& film, bool preview, double pass_seconds,
                        double samples, double accumulate_seconds) {
    // The views other than the beauty are pictures of data: no exposure.
    const auto t0 = Clock::now();
    film.tonemap(m_view == ViewLayer::beauty ? m_exposure : 0.0, m_rgb);
    const double tonemap = seconds_since(t0);
    const auto t1 = Clock::now();
    const std::string jpeg = m_jpeg.encode(m_rgb, film.width(), film.height());
    const double encode = seconds_since(t1);
    json header = {{"type", "frame"},
                   {"seq", ++m_seq},
                   {"width", film.width()},
                   {"height", film.height()},
                   {"full_width", m_width},
                   {"full_height", m_height},
                   {"spp", film.passes()},
                   {"target_spp", m_target_spp},
                   {"preview", preview},
                   {"pass_ms", pass_seconds * 1e3},
                   {"samples_per_s", pass_seconds > 0 ? samples / pass_seconds : 0.0},
                   // Where the rest of a frame's time goes, after the pass (its download included).
                   {"accumulate_ms", accumulate_seconds * 1e3},
                   {"tonemap_ms", tonemap * 1e3},
                   {"encode_ms", encode * 1e3},
                   {"camera", describe_camera(v.camera)},
                   {"camera_from", v.camera_from}};
    if (v.latency_pending) {
        header["latency_ms"] = seconds_since(v.change_received) * 1e3;
        v.latency_pending = false;
    }
    const std::string h = header.dump();
    auto frame = std::make_shared<std::string>();
    frame->resize(4);
    const uint32_t n = uint32_t(h.size());
    for (int i = 0; i < 4; ++i) (*frame)[size_t(i)] = char((n >> (8 * i)) & 0xff);
    *frame += h;
    *frame += jpeg;
    v.last_send = Clock::now();
    ++m_frames_sent;
    m_sink.send_frame(client, std::move(frame));
}

void Viewer::publish_state() {
    json st = describe_scene(*m_scene, m_file_cameras, m_light_scale);
    st["type"] = "state";
    st["scene"] = m_options.scene.filename().string();
    st["backend"] = m_options.backend;
    st["width"] = m_width;
    st["height"] = m_height;
    st["preview_divisor"] = m_divisor;
    st["target_spp"] = m_target_spp;
    st["max_depth"] = m_max_depth;
    st["exposure"] = m_exposure;
    st["view"] = view_layer_name(m_view);
    st["savable"] = m_saver.can_save();
    st["why_not_savable"] = m_saver.why_not();
    st["keyframes"] = m_keyframes.size();
    st["camera"] = describe_camera(m_start_camera);  // where a new page starts
    auto text = std::make_shared<const std::string>(st.dump());
    {
        std::lock_guard lock(m_mutex);
        m_state = text;
    }
    m_sink.send_text(0, text);
}

void Viewer::reply(uint64_t client, const std::string& type, json body) {
    body["type"] = type;
    m_sink.send_text(client, std::make_shared<const std::string>(body.dump()));
}

void Viewer::save(uint64_t client) {
    (void)client;
    SceneEditsToSave e;
    for (size_t i = 0; i < m_volume_edited.size(); ++i)
        if (m_volume_edited[i]) e.volumes.push_back(i);
    for (size_t i = 0; i < m_light_scale.size(); ++i)
        if (m_light_scale[i] != 1.0) e.light_scales.push_back({i, m_light_scale[i]});
    if (m_spp_edited) e.spp = m_target_spp;
    if (m_depth_edited) e.max_depth = m_max_depth;
    if (!m_saver.can_save()) throw Error("save: " + m_saver.why_not());
    const std::vector<std::string> notes = m_saver.save(*m_scene, e);
    spdlog::info("serve: saved {}{}", m_options.scene.string(),
                 notes.empty() ? "" : " (" + std::to_string(notes.size()) + " notes)");
    for (const std::string& n : notes) spdlog::warn("serve: save: {}", n);
    reply(0, "saved", {{"path", m_options.scene.string()}, {"notes", notes}});
}

void Viewer::render_still(uint64_t client, int spp) {
    const int n = spp > 0 ? spp : m_target_spp;
    const fs::path dir = m_options.output_dir.empty() ? m_options.scene.parent_path() : m_options.output_dir;
    fs::path exr;
    for (int k = ++m_stills;; k = ++m_stills) {
        exr = dir / fmt::format("{}.still.{:03d}.exr", m_options.scene.stem().string(), k);
        if (!fs::exists(exr)) break;
    }
    fs::path png = exr;
    png.replace_extension(".png");
    const render::RenderOptions o = options_for(m_width, m_height, n);
    aim_at(client);  // the page's view, as it shows it
    spdlog::info("serve: rendering a still {}x{} at {} spp to {}", m_width, m_height, n, exr.string());
    auto last = Clock::now();
    const auto t0 = Clock::now();
    const Image image = m_full->render(o, [&](uint64_t done, uint64_t total) {
        if (seconds_since(last) < 0.25) return;
        last = Clock::now();
        reply(client, "render_progress", {{"fraction", total ? double(done) / double(total) : 0.0}});
    });
    write_exr(exr, image);
    if (image.channels == 4)
        write_png_premultiplied(png, image, float(m_exposure));
    else
        write_png(png, image, float(m_exposure));
    reply(client, "render_done",
          {{"exr", exr.string()},
           {"png", png.string()},
           {"seconds", seconds_since(t0)},
           {"width", m_width},
           {"height", m_height},
           {"spp", n}});
}

void Viewer::save_keyframes(uint64_t client, double seconds_per_key) {
    const fs::path dir = m_options.scene.parent_path();
    const std::string stem = m_options.scene.stem().string();
    const fs::path path_file = dir / (stem + ".camera_path.gltf");
    const fs::path shot_file = dir / (stem + ".shot.json");
    const int frames = SceneSaver::write_camera_path(path_file, m_keyframes, seconds_per_key,
                                                     m_scene->settings.fps, m_width, m_height);
    // A JSON scene that renders the path: the camera path first (a JSON scene plays the first included
    // animation), then the scene as saved (a JSON scene with the viewer's edits applied, or the file itself).
    json shot;
    std::vector<std::string> notes;
    const std::string ext = m_options.scene.extension().string();
    if (ext == ".json" && m_saver.can_save()) {
        SceneEditsToSave e;
        for (size_t i = 0; i < m_volume_edited.size(); ++i)
            if (m_volume_edited[i]) e.volumes.push_back(i);
        shot = m_saver.apply(*m_scene, e, &notes);
        json includes = json::array({path_file.filename().string()});
        if (shot.contains("include") && shot["include"].is_array())
            for (const json& inc : shot["include"]) includes.push_back(inc);
        shot["include"] = includes;
    } else {
        shot = {{"include", {path_file.filename().string(), m_options.scene.filename().string()}}};
    }
    shot["camera"] = {{"name", "viewer_path"}};
    write_text_atomic(shot_file, shot.dump(2) + "\n");
    const std::string command =
        fmt::format("nerfpt render {} -o out/{}.####.exr --frames 0-{}", shot_file.string(), stem, frames);
    spdlog::info("serve: camera path of {} keyframes written to {} ({})", m_keyframes.size(),
                 shot_file.string(), command);
    reply(client, "keyframes_saved",
          {{"shot", shot_file.string()},
           {"path", path_file.string()},
           {"frames", frames},
           {"command", command},
           {"notes", notes}});
}

}  // namespace npt::serve
