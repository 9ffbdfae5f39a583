#include "capture_record.h"

#include <fmt/format.h>


#include "core/error.h"
#include "core/json_file.h"
#include "core/temp_file.h"

namespace npt::cli {
namespace fs = std::filesystem;

namespace {

constexpr int k_record_version = 1;
const char* const k_stage_order[] = {"curate", "poses", "object", "split", "train", "eval", "isolate", "turntable"};

double num(const nlohmann::json& j, const char* key) {
    const auto it = j.find(key);
    return it != j.end() && it->is_number() ? it->get<double>() : 0.0;
}

}  // namespace

CaptureRecord::CaptureRecord(const fs::path& workdir, const fs::path& video)
    : m_workdir(workdir), m_path(workdir / "capture.json") {
    const std::string video_abs = fs::absolute(video).lexically_normal().string();
    std::error_code ec;
    if (fs::exists(m_path, ec)) {
        try {
            m_json = read_json_file(m_path);
        } catch (const Error& e) {
            throw Error(std::string(e.what()) + "; pass --force to start over");
        }
        if (!m_json.is_object() || !m_json.contains("stages") || !m_json["stages"].is_object())
            throw Error(m_path.string() + ": 'stages': expected an object; pass --force to start over");
        const std::string recorded = m_json.value("video", "");
        if (recorded != video_abs)
            throw Error(m_path.string() + ": this folder holds the capture of '" + recorded +
                        "'; use another --output, or --force to start over with '" + video_abs + "'");
        return;
    }
    m_json = {{"version", k_record_version}, {"video", video_abs}, {"stages", nlohmann::json::object()}};
}

bool CaptureRecord::done(const std::string& stage) const { return m_json["stages"].contains(stage); }

const nlohmann::json& CaptureRecord::stage(const std::string& name) const {
    static const nlohmann::json empty = nlohmann::json::object();
    const auto it = m_json["stages"].find(name);
    return it == m_json["stages"].end() ? empty : *it;
}

void CaptureRecord::finish(const std::string& stage, nlohmann::json result) {
    m_json["stages"][stage] = std::move(result);
    save();
}

void CaptureRecord::forget_from(const std::string& stage) {
    bool later = false;
    for (const char* name : k_stage_order) {
        later = later || stage == name;
        if (later) m_json["stages"].erase(name);
    }
    save();  // at once: the caller is about to remove or replace those stages' files
}

std::string CaptureRecord::markdown() const { return capture_report_markdown(m_json); }

void CaptureRecord::save() const {
    write_text_atomic(m_path, m_json.dump(2) + "\n");
    write_text_atomic(m_workdir / "report.md", capture_report_markdown(m_json));
}

std::string capture_report_markdown(const nlohmann::json& record) {
    const nlohmann::json& st = record.at("stages");
    const auto get = [&](const char* name) {
        return st.contains(name) ? st[name] : nlohmann::json::object();
    };
    std::string md = fmt::format("# nerfpt capture of {}\n\n", record.value("video", "?"));
    md += "| stage | result | time |\n|---|---|---|\n";
    double total = 0;
    if (const auto c = get("curate"); !c.empty()) {
        md += fmt::format("| curate | {} of {} decoded frames kept ({} in the video) | {:.1f} s |\n",
                          c.value("kept", 0), c.value("decoded", 0), c.value("video_frames", 0),
                          num(c, "seconds"));
        total += num(c, "seconds");
    }
    if (const auto p = get("poses"); !p.empty()) {
        md += fmt::format(
            "| poses | COLMAP ({}) registered {} of {} frames, {} points, mean reprojection error {:.3f} px, {} "
            "jumps "
            "in the camera path | {:.1f} s (extraction {:.1f}, matching {:.1f}, mapping {:.1f}{}) |\n",
            p.value("quality", "best"), p.value("registered", 0), p.value("frames", 0), p.value("points", 0),
            num(p, "reprojection_px"), p.value("path_jumps", 0), num(p, "seconds"), num(p, "extraction_seconds"),
            num(p, "matching_seconds"), num(p, "mapping_seconds"),
            p.contains("loop_closure_seconds") ? fmt::format(", loops {:.1f}", num(p, "loop_closure_seconds"))
                                               : std::string());
        total += num(p, "seconds");
    }
    if (const auto o = get("object"); !o.empty()) {
        if (o.value("found", false)) {
            const auto& up = o["up"];
            md += fmt::format("| object | up ({:.3f}, {:.3f}, {:.3f}), height {:.4g} {}, {} points on the supporting "
                              "plane, {} on the object | {:.1f} s |\n",
                              up[0].get<double>(), up[1].get<double>(), up[2].get<double>(),
                              o.value("metric", false) ? o.value("height_m", 0.0) : num(o, "height"),
                              o.value("metric", false) ? "m" : "capture units", o.value("plane_inliers", 0),
                              o.value("seed_points", 0), num(o, "seconds"));
        } else {
            md += fmt::format("| object | not found: {} | |\n", o.value("reason", "?"));
        }
    }
    if (const auto s = get("split"); !s.empty())
        md += fmt::format("| split | {} training frames, {} held out (every {}th) | |\n", s.value("train", 0),
                          s.value("test", 0), s.value("every", 0));
    if (const auto t = get("train"); !t.empty()) {
        md += fmt::format("| train | {} steps at {}x{} (downscale {}) | {:.1f} s |\n", t.value("steps", 0),
                          t.value("width", 0), t.value("height", 0), t.value("downscale", 0),
                          num(t, "seconds"));
        total += num(t, "seconds");
    }
    if (const auto e = get("eval"); !e.empty()) {
        md += fmt::format("| held-out views | {} frames: PSNR {:.2f} dB, SSIM {:.4f} (eval/) | {:.1f} s |\n",
                          e.value("views", 0), num(e, "psnr"), num(e, "ssim"), num(e, "seconds"));
        total += num(e, "seconds");
    }
    if (const auto i = get("isolate"); !i.empty()) {
        md += fmt::format("| isolate | model.npt: the object alone, {} of {} occupied cells kept ({} outside the box or "
                          "under the plane, {} in {} floaters){} | {:.1f} s |\n",
                          i.value("occupied_after", 0), i.value("occupied_before", 0), i.value("cut_by_region", 0),
                          i.value("cut_as_floaters", 0), i.value("floaters", 0),
                          i.value("scene_model", "").empty() ? "" : "; the whole scene: model_scene.npt",
                          num(i, "seconds"));
        total += num(i, "seconds");
    }
    if (const auto v = get("turntable"); !v.empty()) {
        md += fmt::format("| turntable | {}, {} frames of {} | {:.1f} s |\n", v.value("file", ""),
                          v.value("frames", 0), v.value("res", ""), num(v, "seconds"));
        total += num(v, "seconds");
    }
    md += fmt::format(
        "\nTotal: {:.1f} s. The model is model.npt; `nerfpt info model.npt` says where its content "
        "lies, to place it in a scene.\n",
        total);
    return md;
}

}  // namespace npt::cli
