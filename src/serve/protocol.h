// The viewer's messages from the page (JSON text over the WebSocket), parsed and range-checked in one place
// so that the server acts only on well-formed requests. Everything here is plain C++ (no Boost): the fuzz
// harness (fuzz/fuzz_serve_message.cpp) and the unit tests link it alone.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace npt::serve {

// Largest message the page may send (the WebSocket refuses bigger frames before they are buffered).
constexpr size_t k_max_message_bytes = 64 * 1024;
// Bounds that keep a message from asking for unbounded work.
constexpr int k_max_target_spp = 1 << 16;
constexpr int k_max_viewer_depth = 64;
constexpr int k_max_preview_divisor = 16;
constexpr int k_max_keyframes = 1000;
constexpr double k_max_scale_factor = 1e6;  // density, emission and light scales: 0..1e6

using V3 = std::array<double, 3>;
using V4 = std::array<double, 4>;

// The viewer's camera: position and orientation (three.js's camera looks down its -Z, up +Y), vertical field
// of view in degrees.
struct CameraMsg {
    V3 position{};
    V3 forward{0, 0, -1};
    V3 up{0, 1, 0};
    double fov_deg = 40;
};
// Jump to the scene's camera `index` (scene.cameras).
struct UseCameraMsg {
    int index = 0;
};
// Edits of volume `index`: any subset of its placement (world translation, rotation quaternion x y z w, scale
// of the node) and what fills it. `crop_clear` removes the crop box (the model's whole box).
struct VolumeMsg {
    int index = 0;
    std::optional<V3> translation;
    std::optional<V4> rotation;
    std::optional<V3> scale;
    std::optional<double> density_scale;
    std::optional<double> emission_scale;
    std::optional<std::pair<V3, V3>> crop;  // min, max in model space
    bool crop_clear = false;
    std::optional<std::string> shading;  // "relit" or "emissive"
};
// Scale of light `index`'s intensity (punctual lights) relative to the loaded scene.
struct LightMsg {
    int index = 0;
    double intensity_scale = 1;
};
// Render settings of the viewer and of what is saved.
struct SettingsMsg {
    std::optional<int> spp;              // target samples per pixel of the refinement (and the saved scene's)
    std::optional<int> max_depth;        // bounces
    std::optional<double> exposure;      // stops, the page's tone map only
    std::optional<int> preview_divisor;  // resolution divisor while the camera moves
    std::optional<std::string>
        view;  // what the page shows: beauty, alpha, albedo, normal, depth (view_layer.h)
};
struct SaveMsg {};
// A still at the scene's full resolution and `spp` (0: the settings') written beside the scene.
struct RenderStillMsg {
    int spp = 0;
};
// Camera path: add the current viewer camera as a keyframe, clear them, or save them as a glTF animation.
struct KeyframeAddMsg {};
struct KeyframesClearMsg {};
struct KeyframesSaveMsg {
    double seconds_per_key = 1.0;
};

using ClientMessage = std::variant<CameraMsg, UseCameraMsg, VolumeMsg, LightMsg, SettingsMsg, SaveMsg,
                                   RenderStillMsg, KeyframeAddMsg, KeyframesClearMsg, KeyframesSaveMsg>;

// Parses one message. Throws npt::Error with a one-line reason ("camera.position: expected 3 finite numbers")
// for anything malformed, oversized or out of range; never anything else.
ClientMessage parse_client_message(std::string_view text);

}  // namespace npt::serve
