// The viewer's render worker: owns the loaded scene and its prepared renderers (the same SceneRenderer that
// `nerfpt render` uses, CPU or OptiX), applies the pages' messages on its own thread, and renders
// progressively: after any change one pass at a reduced resolution (the preview), then 1-sample passes at
// full resolution accumulated until the target spp. Every page has its own camera and film: a page's camera
// move restarts only its film, a scene edit every page's; the worker takes the pages in turn. Each frame is
// tone-mapped, JPEG-encoded and handed to the sink (the server) for its page.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "render/backend/render_backend.h"
#include "scene/scene.h"
#include "serve/frame_encoder.h"
#include "serve/page_io.h"
#include "serve/protocol.h"
#include "serve/scene_save.h"
#include "serve/view_layer.h"

namespace npt::serve {

struct ViewerOptions {
    std::filesystem::path scene;
    std::string backend = "cpu";       // resolved: "cpu" or "optix"
    int width = 0, height = 0;         // 0: the scene's
    int threads = 0;                   // CPU render threads, 0 = all
    int preview_divisor = 0;           // 0: 4 on the CPU, 1 (no preview) on OptiX
    int target_spp = 0;                // 0: the scene's spp
    std::filesystem::path output_dir;  // stills; empty: beside the scene
};

class Viewer final : public PageHandler {
  public:
    // Loads the scene and prepares its renderers. Throws npt::Error for a scene nerfpt render would refuse.
    Viewer(const ViewerOptions& options, ViewerSink& sink);
    ~Viewer() override;
    Viewer(const Viewer&) = delete;
    Viewer& operator=(const Viewer&) = delete;

    void start();
    void stop();
    // From any thread: queued for the worker. A queue over k_max_queue drops the oldest camera message.
    void post(uint64_t client, ClientMessage message) override;
    void page_opened(uint64_t client) override;
    void page_closed(uint64_t client) override;
    // The state a newly connected page starts from (JSON text: {"type": "state", ...}).
    std::shared_ptr<const std::string> state() const override;
    // Frames handed to the sink so far (tests).
    uint64_t frames_sent() const { return m_frames_sent; }

    static constexpr size_t k_max_queue = 1024;

  private:
    struct Pending {
        uint64_t client;
        ClientMessage message;
        std::chrono::steady_clock::time_point received;
    };
    struct Cancelled {};
    using Clock = std::chrono::steady_clock;
    // One page's view: its camera and the film accumulated from it.
    struct PageView {
        scene::Camera camera;
        uint64_t camera_from = 0;  // the page itself after its own move, 0 after the server placed the camera
        Accumulator film;
        float depth_range = 0.0f;  // the depth view's black (0: not yet taken from a pass since the last change)
        bool dirty = true;         // the next frame is a preview after a change
        bool latency_pending = false;
        Clock::time_point change_received;  // when the oldest unserved change arrived
        Clock::time_point last_send;
        // A GPU pass cannot be cancelled: after a preview the first full pass waits this long for the next
        // move, so that a drag's frames are previews, not a pass and then a preview.
        Clock::time_point refine_after;
    };
    enum class Restart { none, page, all };  // whose film a message restarts

    void run();
    void prepare();                 // (re)builds the renderers for the scene as it is now
    Restart handle(const Pending& p);
    void apply_pose_change(bool camera, bool lights, bool volumes);
    PageView& page(uint64_t client);  // made on first use (a page's messages may come before its opening)
    bool has_work(Clock::time_point now, Clock::time_point* wake_at) const;
    PageView* next_page(uint64_t* client);  // the next page to render for, in turn; null when none needs it
    void aim_at(uint64_t client);           // the renderers' camera becomes the page's
    void render_preview(uint64_t client, PageView& v);
    void render_pass(uint64_t client, PageView& v);
    void render_still(uint64_t client, int spp);
    void save(uint64_t client);
    void save_keyframes(uint64_t client, double seconds_per_key);
    // accumulate_seconds: the pass's addition to `film`, reported beside the tone map's and the encoder's time.
    void send_frame(uint64_t client, PageView& v, const Accumulator& film, bool preview, double pass_seconds,
                    double samples, double accumulate_seconds = 0);
    // One pass of `renderer` as the page shows it (the beauty, or the view's layer made viewable).
    Image render_view(render::SceneRenderer& renderer, const render::RenderOptions& options, bool cancellable,
                      float& depth_range);
    void publish_state();
    void reply(uint64_t client, const std::string& type, nlohmann::json body);
    render::RenderOptions options_for(int width, int height, int spp) const;

    ViewerOptions m_options;
    ViewerSink& m_sink;
    std::unique_ptr<scene::Scene> m_scene;  // renderers hold a reference: never moved
    size_t m_file_cameras = 0;              // scene.cameras before the viewer's own, appended last
    SceneSaver m_saver;
    std::unique_ptr<render::SceneRenderer> m_full, m_preview;
    int m_width = 0, m_height = 0;
    int m_divisor = 1;
    int m_target_spp = 1;
    int m_max_depth = 16;
    double m_exposure = 0;
    ViewLayer m_view = ViewLayer::beauty;
    bool m_spp_edited = false, m_depth_edited = false;
    std::vector<bool> m_volume_edited;
    std::vector<Rgb> m_light_base;
    std::vector<double> m_light_scale;
    std::vector<scene::Camera> m_keyframes;
    uint64_t m_seed = 0;
    int m_stills = 0;

    scene::Camera m_start_camera;        // where a new page's view starts
    std::map<uint64_t, PageView> m_pages;  // the worker thread's
    static constexpr uint64_t k_nobody = ~uint64_t(0);
    uint64_t m_aimed_at = k_nobody;  // the page whose camera the renderers hold
    uint64_t m_last_rendered = 0;    // the page rendered for last: the next turn starts after it
    std::vector<uint8_t> m_rgb;
    JpegEncoder m_jpeg;
    uint64_t m_seq = 0;

    mutable std::mutex m_mutex;
    std::condition_variable m_wake;
    std::deque<Pending> m_queue;
    std::vector<uint64_t> m_opened, m_closed;  // pages, in the order the server saw them
    std::atomic<bool> m_interrupt{false};  // a message arrived: cancel the CPU pass in flight
    bool m_stop = false;
    std::shared_ptr<const std::string> m_state;
    std::atomic<uint64_t> m_frames_sent{0};
    std::thread m_thread;
};

}  // namespace npt::serve
