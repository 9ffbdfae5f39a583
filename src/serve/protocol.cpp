#include "serve/protocol.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/json_file.h"
#include "serve/view_layer.h"

namespace npt::serve {
namespace {
using json = nlohmann::json;

constexpr double k_max_coordinate = 1e9;  // viewer positions; the scene's own bound is checked when applied

[[noreturn]] void fail(const std::string& field, const std::string& why) { throw Error(field + ": " + why); }

double number(const json& v, const std::string& field, double lo, double hi) {
    if (!v.is_number()) fail(field, "expected a number");
    const double x = v.get<double>();
    if (!std::isfinite(x) || x < lo || x > hi)
        fail(field, "expected a number in [" + json(lo).dump() + ", " + json(hi).dump() + "]");
    return x;
}

int integer(const json& v, const std::string& field, int lo, int hi) {
    if (!v.is_number_integer()) fail(field, "expected a whole number");
    // As int64 first: a huge unsigned value must not wrap into range.
    if (v.is_number_unsigned() && v.get<uint64_t>() > uint64_t(hi)) fail(field, "out of range");
    const int64_t x = v.get<int64_t>();
    if (x < lo || x > hi)
        fail(field, "expected a whole number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return int(x);
}

template <size_t N>
std::array<double, N> numbers(const json& v, const std::string& field, double lo, double hi) {
    if (!v.is_array() || v.size() != N) fail(field, "expected an array of " + std::to_string(N) + " numbers");
    std::array<double, N> out{};
    for (size_t i = 0; i < N; ++i) out[i] = number(v[i], field + "[" + std::to_string(i) + "]", lo, hi);
    return out;
}

double norm(const V3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

void check_keys(const json& j, const std::string& type, std::initializer_list<const char*> allowed) {
    for (auto it = j.begin(); it != j.end(); ++it) {
        bool ok = it.key() == "type";
        for (const char* a : allowed) ok = ok || it.key() == a;
        if (!ok) fail(type + "." + it.key(), "unknown field");
    }
}

CameraMsg parse_camera(const json& j) {
    check_keys(j, "camera", {"position", "forward", "up", "fov_deg"});
    CameraMsg m;
    if (!j.contains("position") || !j.contains("forward")) fail("camera", "needs position and forward");
    m.position = numbers<3>(j["position"], "camera.position", -k_max_coordinate, k_max_coordinate);
    m.forward = numbers<3>(j["forward"], "camera.forward", -1e6, 1e6);
    if (j.contains("up")) m.up = numbers<3>(j["up"], "camera.up", -1e6, 1e6);
    if (j.contains("fov_deg")) m.fov_deg = number(j["fov_deg"], "camera.fov_deg", 1, 170);
    const double f = norm(m.forward), u = norm(m.up);
    if (!(f > 1e-9)) fail("camera.forward", "must not be zero");
    if (!(u > 1e-9)) fail("camera.up", "must not be zero");
    const V3 c{m.forward[1] * m.up[2] - m.forward[2] * m.up[1],
               m.forward[2] * m.up[0] - m.forward[0] * m.up[2],
               m.forward[0] * m.up[1] - m.forward[1] * m.up[0]};
    if (!(norm(c) > 1e-6 * f * u)) fail("camera.up", "must not be parallel to camera.forward");
    return m;
}

VolumeMsg parse_volume(const json& j) {
    check_keys(
        j, "volume",
        {"index", "translation", "rotation", "scale", "density_scale", "emission_scale", "crop", "shading"});
    VolumeMsg m;
    if (!j.contains("index")) fail("volume.index", "missing");
    m.index = integer(j["index"], "volume.index", 0, 1 << 20);
    if (j.contains("translation"))
        m.translation =
            numbers<3>(j["translation"], "volume.translation", -k_max_coordinate, k_max_coordinate);
    if (j.contains("rotation")) {
        V4 q = numbers<4>(j["rotation"], "volume.rotation", -2, 2);
        const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (!(n > 1e-6)) fail("volume.rotation", "the quaternion [x, y, z, w] is zero");
        for (double& c : q) c /= n;
        m.rotation = q;
    }
    if (j.contains("scale")) {
        const V3 s = numbers<3>(j["scale"], "volume.scale", -k_max_scale_factor, k_max_scale_factor);
        for (double c : s)
            if (!(std::abs(c) >= 1e-6)) fail("volume.scale", "each component must be at least 1e-6 in size");
        m.scale = s;
    }
    if (j.contains("density_scale"))
        m.density_scale = number(j["density_scale"], "volume.density_scale", 0, k_max_scale_factor);
    if (j.contains("emission_scale"))
        m.emission_scale = number(j["emission_scale"], "volume.emission_scale", 0, k_max_scale_factor);
    if (j.contains("crop")) {
        const json& c = j["crop"];
        if (c.is_null()) {
            m.crop_clear = true;
        } else {
            if (!c.is_object() || !c.contains("min") || !c.contains("max") || c.size() != 2)
                fail("volume.crop", "expected {\"min\": [x, y, z], \"max\": [x, y, z]} or null");
            const V3 lo = numbers<3>(c["min"], "volume.crop.min", -1e4, 1e4);
            const V3 hi = numbers<3>(c["max"], "volume.crop.max", -1e4, 1e4);
            for (int k = 0; k < 3; ++k)
                if (!(hi[k] > lo[k])) fail("volume.crop", "max must exceed min on every axis");
            m.crop = std::make_pair(lo, hi);
        }
    }
    if (j.contains("shading")) {
        if (!j["shading"].is_string()) fail("volume.shading", "expected \"relit\" or \"emissive\"");
        const std::string s = j["shading"].get<std::string>();
        if (s != "relit" && s != "emissive") fail("volume.shading", "expected \"relit\" or \"emissive\"");
        m.shading = s;
    }
    return m;
}

SettingsMsg parse_settings(const json& j) {
    check_keys(j, "settings", {"spp", "max_depth", "exposure", "preview_divisor", "view"});
    SettingsMsg m;
    if (j.contains("spp")) m.spp = integer(j["spp"], "settings.spp", 1, k_max_target_spp);
    if (j.contains("max_depth"))
        m.max_depth = integer(j["max_depth"], "settings.max_depth", 0, k_max_viewer_depth);
    if (j.contains("exposure")) m.exposure = number(j["exposure"], "settings.exposure", -20, 20);
    if (j.contains("preview_divisor"))
        m.preview_divisor =
            integer(j["preview_divisor"], "settings.preview_divisor", 1, k_max_preview_divisor);
    if (j.contains("view")) {
        if (!j["view"].is_string() || !parse_view_layer(j["view"].get<std::string>()))
            fail("settings.view", "expected \"beauty\", \"alpha\", \"albedo\", \"normal\" or \"depth\"");
        m.view = j["view"].get<std::string>();
    }
    return m;
}

}  // namespace

ClientMessage parse_client_message(std::string_view text) {
    if (text.size() > k_max_message_bytes)
        throw Error("message: " + std::to_string(text.size()) + " bytes, more than the " +
                    std::to_string(k_max_message_bytes) + " allowed");
    const json j = parse_json_text(text, "message");
    if (!j.is_object()) fail("message", "expected a JSON object {\"type\": ...}");
    if (!j.contains("type") || !j["type"].is_string()) fail("message.type", "missing or not a string");
    const std::string type = j["type"].get<std::string>();
    if (type == "camera") return parse_camera(j);
    if (type == "use_camera") {
        check_keys(j, type, {"index"});
        if (!j.contains("index")) fail("use_camera.index", "missing");
        return UseCameraMsg{integer(j["index"], "use_camera.index", 0, 1 << 20)};
    }
    if (type == "volume") return parse_volume(j);
    if (type == "light") {
        check_keys(j, type, {"index", "intensity_scale"});
        if (!j.contains("index") || !j.contains("intensity_scale"))
            fail("light", "needs index and intensity_scale");
        return LightMsg{integer(j["index"], "light.index", 0, 1 << 20),
                        number(j["intensity_scale"], "light.intensity_scale", 0, k_max_scale_factor)};
    }
    if (type == "settings") return parse_settings(j);
    if (type == "save") {
        check_keys(j, type, {});
        return SaveMsg{};
    }
    if (type == "render") {
        check_keys(j, type, {"spp"});
        RenderStillMsg m;
        if (j.contains("spp")) m.spp = integer(j["spp"], "render.spp", 1, k_max_target_spp);
        return m;
    }
    if (type == "keyframe_add") {
        check_keys(j, type, {});
        return KeyframeAddMsg{};
    }
    if (type == "keyframes_clear") {
        check_keys(j, type, {});
        return KeyframesClearMsg{};
    }
    if (type == "keyframes_save") {
        check_keys(j, type, {"seconds_per_key"});
        KeyframesSaveMsg m;
        if (j.contains("seconds_per_key"))
            m.seconds_per_key = number(j["seconds_per_key"], "keyframes_save.seconds_per_key", 0.01, 3600);
        return m;
    }
    fail("message.type", "unknown type '" + type.substr(0, 40) + "'");
}

}  // namespace npt::serve
