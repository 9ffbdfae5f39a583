// The viewer's render worker: owns the loaded scene and its prepared renderers (the same SceneRenderer that
// `nerfpt render` uses, CPU or OptiX), applies the page's messages on its own thread, and renders
// progressively: after any change one pass at a reduced resolution (the preview), then 1-sample passes at
// full resolution accumulated until the target spp. Each frame is tone-mapped, JPEG-encoded and handed to the
// sink (the server).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
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

    void run();
    void prepare();                 // (re)builds the renderers for the scene as it is now
    bool handle(const Pending& p);  // true when the image changes
    void apply_pose_change(bool camera, bool lights, bool volumes);
    void render_preview();
    void render_pass();
    void render_still(uint64_t client, int spp);
    void save(uint64_t client);
    void save_keyframes(uint64_t client, double seconds_per_key);
    void send_frame(const Accumulator& film, bool preview, double pass_seconds, double samples);
    // One pass of `renderer` as the page shows it (the beauty, or the view's layer made viewable).
    Image render_view(render::SceneRenderer& renderer, const render::RenderOptions& options,
                      bool cancellable);
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
    float m_depth_range =
        0.0f;  // the depth view's black (0: not yet taken from a pass since the last change)
    bool m_spp_edited = false, m_depth_edited = false;
    std::vector<bool> m_volume_edited;
    std::vector<Rgb> m_light_base;
    std::vector<double> m_light_scale;
    std::vector<scene::Camera> m_keyframes;
    uint64_t m_camera_from = 0;  // the client whose camera message moved the view last
    uint64_t m_seed = 0;
    int m_stills = 0;

    Accumulator m_film;
    std::vector<uint8_t> m_rgb;
    JpegEncoder m_jpeg;
    bool m_dirty = true;                                      // the next frame is a preview after a change
    std::chrono::steady_clock::time_point m_change_received;  // when the oldest unserved change arrived
    bool m_change_pending_latency = false;
    std::chrono::steady_clock::time_point m_last_send;
    // A GPU pass cannot be cancelled: after a preview the first full pass waits this long for the next move, so
    // that a drag's frames are previews, not a pass and then a preview.
    std::chrono::steady_clock::time_point m_refine_after;
    uint64_t m_seq = 0;

    mutable std::mutex m_mutex;
    std::condition_variable m_wake;
    std::deque<Pending> m_queue;
    std::atomic<bool> m_interrupt{false};  // a message arrived: cancel the CPU pass in flight
    bool m_stop = false;
    std::shared_ptr<const std::string> m_state;
    std::atomic<uint64_t> m_frames_sent{0};
    std::thread m_thread;
};

}  // namespace npt::serve
