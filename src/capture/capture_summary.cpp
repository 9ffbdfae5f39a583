#include "capture/capture_summary.h"

#include <fmt/format.h>

#include <nlohmann/json.hpp>

namespace npt::capture {
namespace {

double num(const nlohmann::json& j, const char* key) {
    const auto it = j.find(key);
    return it != j.end() && it->is_number() ? it->get<double>() : 0.0;
}

template <typename T>
T value(const nlohmann::json& j, const char* key, T fallback) {
    const auto it = j.find(key);
    if (it == j.end()) return fallback;
    try {
        return it->get<T>();
    } catch (const nlohmann::json::exception&) {
        return fallback;
    }
}

std::string text(const nlohmann::json& j, const char* key, const char* fallback = "") {
    return value<std::string>(j, key, fallback);
}

int integer(const nlohmann::json& j, const char* key) {
    const auto it = j.find(key);
    return it != j.end() && it->is_number() ? it->get<int>() : 0;
}

double component(const nlohmann::json& v, size_t i) {
    return v.is_array() && v.size() > i && v[i].is_number() ? v[i].get<double>() : 0.0;
}

CaptureStageRow row(const char* stage, const char* label, std::string result, const nlohmann::json& j,
                    bool counted = true) {
    CaptureStageRow r{stage, label, std::move(result), {}, num(j, "seconds"), true, counted};
    r.time = fmt::format("{:.1f} s", r.seconds);
    return r;
}

CaptureStageRow untimed(const char* stage, const char* label, std::string result) {
    return CaptureStageRow{stage, label, std::move(result), {}, 0.0, false, false};
}

}  // namespace

std::vector<CaptureStageRow> capture_stage_rows(const nlohmann::json& record) {
    std::vector<CaptureStageRow> rows;
    if (!record.is_object() || !record.contains("stages") || !record["stages"].is_object()) return rows;
    const nlohmann::json& st = record["stages"];
    const auto get = [&](const char* name) {
        const auto it = st.find(name);
        return it != st.end() && it->is_object() ? *it : nlohmann::json::object();
    };
    if (const auto c = get("curate"); !c.empty())
        rows.push_back(row("curate", "curate",
                           fmt::format("{} of {} decoded frames kept ({} in the video)", integer(c, "kept"),
                                       integer(c, "decoded"), integer(c, "video_frames")),
                           c));
    if (const auto p = get("poses"); !p.empty()) {
        CaptureStageRow r = row(
            "poses", "poses",
            fmt::format(
                "COLMAP ({}) registered {} of {} frames, {} points, mean reprojection error {:.3f} px, {} "
                "jumps in the camera path",
                text(p, "quality", "best"), integer(p, "registered"), integer(p, "frames"),
                integer(p, "points"), num(p, "reprojection_px"), integer(p, "path_jumps")),
            p);
        r.time = fmt::format(
            "{:.1f} s (extraction {:.1f}, matching {:.1f}, mapping {:.1f}{})", r.seconds,
            num(p, "extraction_seconds"), num(p, "matching_seconds"), num(p, "mapping_seconds"),
            p.contains("loop_closure_seconds") ? fmt::format(", loops {:.1f}", num(p, "loop_closure_seconds"))
                                               : std::string());
        rows.push_back(std::move(r));
    }
    if (const auto o = get("object"); !o.empty()) {
        if (value(o, "found", false)) {
            const nlohmann::json up = o.value("up", nlohmann::json::array());
            const bool metric = value(o, "metric", false);
            rows.push_back(row(
                "object", "object",
                fmt::format("up ({:.3f}, {:.3f}, {:.3f}), height {:.4g} {}, {} points on the "
                            "supporting plane, {} on the object",
                            component(up, 0), component(up, 1), component(up, 2),
                            metric ? num(o, "height_m") : num(o, "height"), metric ? "m" : "capture units",
                            integer(o, "plane_inliers"), integer(o, "seed_points")),
                o, /*counted=*/false));
        } else {
            rows.push_back(untimed("object", "object", "not found: " + text(o, "reason", "?")));
        }
    }
    if (const auto s = get("split"); !s.empty())
        rows.push_back(untimed("split", "split",
                               fmt::format("{} training frames, {} held out (every {}th)",
                                           integer(s, "train"), integer(s, "test"), integer(s, "every"))));
    if (const auto t = get("train"); !t.empty())
        rows.push_back(row(
            "train", "train",
            fmt::format("{} steps at {}x{} (downscale {}){}", value<uint64_t>(t, "steps", 0),
                        integer(t, "width"), integer(t, "height"), integer(t, "downscale"),
                        num(t, "subject_rays") > 0 ? fmt::format(", {:.0f}% of the rays on the object's box",
                                                                 100.0 * num(t, "subject_rays"))
                                                   : std::string()),
            t));
    if (const auto e = get("eval"); !e.empty())
        rows.push_back(row("eval", "held-out views",
                           fmt::format("{} frames: PSNR {:.2f} dB, SSIM {:.4f} of the whole frames (eval/)",
                                       integer(e, "views"), num(e, "psnr"), num(e, "ssim")),
                           e));
    if (const auto i = get("isolate"); !i.empty())
        rows.push_back(
            row("isolate", "isolate",
                fmt::format("model.npt: the object alone, {} of {} occupied cells kept ({} outside the "
                            "box or under the plane, {} of the table around the foot, {} in {} floaters){}",
                            value<uint64_t>(i, "occupied_after", 0), value<uint64_t>(i, "occupied_before", 0),
                            value<uint64_t>(i, "cut_by_region", 0), value<uint64_t>(i, "cut_off_footprint", 0),
                            value<uint64_t>(i, "cut_as_floaters", 0),
                            value<uint64_t>(i, "floaters", 0),
                            text(i, "scene_model").empty() ? "" : "; the whole scene: model_scene.npt"),
                i));
    if (const auto v = get("turntable"); !v.empty())
        rows.push_back(row(
            "turntable", "turntable",
            fmt::format("{}, {} frames of {}", text(v, "file"), integer(v, "frames"), text(v, "res")), v));
    return rows;
}

double capture_total_seconds(const std::vector<CaptureStageRow>& rows) {
    double total = 0;
    for (const CaptureStageRow& r : rows)
        if (r.counted) total += r.seconds;
    return total;
}

}  // namespace npt::capture
