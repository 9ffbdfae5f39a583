#include "serve/capture_report.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>

#include "capture/capture_summary.h"
#include "core/error.h"
#include "core/json_file.h"
#include "serve/http_util.h"

namespace npt::serve {
namespace fs = std::filesystem;

namespace {

constexpr std::string_view k_prefix = "/capture/";
constexpr size_t k_max_eval_files = 100000;  // a folder listing this long is not eval's

// A regular file itself, not a symbolic link to one (which could lead out of the folder).
bool plain_file(const fs::path& p) {
    std::error_code ec;
    return fs::symlink_status(p, ec).type() == fs::file_type::regular;
}

// A name that stays in its folder: not empty, no separator, not "." or "..".
bool plain_name(const std::string& name) {
    return !name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos &&
           name.find('\\') == std::string::npos && name.find('\0') == std::string::npos;
}

std::string content_type_of(const std::string& name) {
    const std::string ext = fs::path(name).extension().string();
    if (ext == ".png") return "image/png";
    if (ext == ".mp4") return "video/mp4";
    if (ext == ".json") return "application/json";
    return "text/plain; charset=utf-8";  // report.md: shown as text, not downloaded
}

std::string url_of(std::string_view under, const std::string& name) {
    return std::string(k_prefix) + std::string(under) + percent_encode_segment(name);
}

// A metric per view: a number, or null (eval writes an infinite PSNR as null).
nlohmann::json metric(const nlohmann::json& image, const char* key, const std::string& where) {
    const auto it = image.find(key);
    if (it == image.end() || it->is_null()) return nullptr;
    if (!it->is_number() || !std::isfinite(it->get<double>()))
        throw Error(where + "." + key + ": expected a number or null, got " + it->dump());
    return *it;
}

}  // namespace

CaptureReport::CaptureReport(const fs::path& dir) {
    std::error_code ec;
    m_dir = fs::weakly_canonical(fs::absolute(dir), ec);
    if (ec) m_dir = fs::absolute(dir).lexically_normal();
    const fs::path record_file = m_dir / "capture.json";
    const std::string rf = record_file.string();
    if (!fs::exists(record_file, ec))
        throw Error(dir.string() +
                    ": not a capture folder: it has no capture.json (nerfpt serve takes a scene, a "
                    "model .npt or the folder `nerfpt capture VIDEO -o DIR` wrote)");
    const nlohmann::json record = read_json_file(record_file);
    if (!record.is_object()) throw Error(rf + ": expected a JSON object (nerfpt capture's record)");
    if (record.contains("version") && record["version"] != 1)
        throw Error(rf + ": 'version': " + record["version"].dump() +
                    " is not supported (this nerfpt reads 1)");
    if (!record.contains("stages") || !record["stages"].is_object())
        throw Error(rf + ": 'stages': expected an object (nerfpt capture's record of its finished stages)");
    const nlohmann::json& stages = record["stages"];
    for (const auto& [name, value] : stages.items())
        if (!value.is_object()) throw Error(rf + ": 'stages." + name + "': expected an object");
    const std::string video = record.contains("video") && record["video"].is_string()
                                  ? record["video"].get<std::string>()
                                  : std::string("?");

    m_model = m_dir / "model.npt";
    if (!fs::exists(m_model, ec)) {
        std::string missing;
        for (const char* s : capture::k_capture_stages) {
            if (!stages.contains(s)) {
                missing = s;
                break;
            }
            if (std::string_view(s) == "train") break;
        }
        const std::string again =
            fmt::format("run `nerfpt capture {} -o {}` again to finish it", video, dir.string());
        if (!missing.empty())
            throw Error(fmt::format(
                "{}: an unfinished capture: no model.npt yet, its '{}' stage is not recorded ({})", rf,
                missing, again));
        throw Error(fmt::format("{}: not found, though {} records the 'train' stage ({})", m_model.string(),
                                rf, again));
    }
    if (fs::is_directory(m_model, ec)) throw Error(m_model.string() + ": a folder, not a model file");

    if (const auto o = stages.find("object"); o != stages.end()) {
        const auto found = o->find("found");
        if (found != o->end() && found->is_boolean() && found->get<bool>() && o->contains("model_frame"))
            m_frame = nerf::object_frame_from_json((*o)["model_frame"], rf + ": stages.object.model_frame");
    }

    // What report.md says, row for row.
    const std::vector<capture::CaptureStageRow> rows = capture::capture_stage_rows(record);
    nlohmann::json table = nlohmann::json::array();
    for (const char* s : capture::k_capture_stages) {
        nlohmann::json e = {{"name", s}, {"state", "skipped"}, {"note", "not run"}, {"seconds", nullptr}};
        for (const capture::CaptureStageRow& r : rows)
            if (r.stage == s) {
                e = {{"name", s},
                     {"label", r.label},
                     {"state", "done"},
                     {"note", r.result},
                     {"seconds", r.timed ? nlohmann::json(r.seconds) : nlohmann::json(nullptr)},
                     {"time", r.time}};
            }
        table.push_back(std::move(e));
    }
    m_report = {{"title", "nerfpt capture of " + video},
                {"video", video},
                {"folder", m_dir.string()},
                {"model", "model.npt"},
                {"stages", std::move(table)},
                {"total_seconds", capture::capture_total_seconds(rows)},
                {"eval", nullptr},
                {"turntable", nullptr},
                {"report_md", nullptr},
                {"object", nullptr},
                {"notes", nlohmann::json::array()}};
    if (const auto i = stages.find("isolate"); i != stages.end()) {
        const auto sm = i->find("scene_model");
        if (sm != i->end() && sm->is_string() && !sm->get<std::string>().empty())
            m_report["scene_model"] = *sm;
    }
    if (m_frame) {
        const nlohmann::json& o = stages["object"];
        m_report["object"] = {{"metric", m_frame->metric},
                              {"height", o.contains("height") ? o["height"] : nlohmann::json(nullptr)},
                              {"height_m", o.contains("height_m") ? o["height_m"] : nlohmann::json(nullptr)}};
    }

    if (plain_file(m_dir / "report.md")) {
        add_file("report.md", content_type_of("report.md"));
        m_report["report_md"] = url_of("", "report.md");
    }
    read_eval(stages);
    if (const auto t = stages.find("turntable"); t != stages.end()) {
        const std::string field = rf + ": stages.turntable.file";
        const auto f = t->find("file");
        if (f == t->end() || !f->is_string()) throw Error(field + ": expected a file name");
        const std::string name = f->get<std::string>();
        if (!plain_name(name))
            throw Error(field + ": '" + name + "' is not a file name in the capture's folder");
        if (const auto e = t->find("elevation_deg"); e != t->end() && e->is_number())
            m_elevation_deg = e->get<double>();
        if (plain_file(m_dir / name)) {
            add_file(name, content_type_of(name));
            m_report["turntable"] = {{"url", url_of("", name)},
                                     {"file", name},
                                     {"frames", t->value("frames", nlohmann::json(nullptr))},
                                     {"res", t->value("res", nlohmann::json(nullptr))},
                                     {"object", t->value("object", nlohmann::json(nullptr))}};
        } else {
            m_report["notes"].push_back(name +
                                        ": not in the folder (or not a regular file), though capture.json "
                                        "records the turntable stage");
        }
    }
    for (const auto& n : m_report["notes"]) spdlog::warn("{}: {}", m_dir.string(), n.get<std::string>());
    m_report_text = m_report.dump();
}

void CaptureReport::read_eval(const nlohmann::json& stages) {
    const fs::path eval = m_dir / "eval";
    std::error_code ec;
    const fs::file_type type = fs::symlink_status(eval, ec).type();
    const bool recorded = stages.contains("eval");
    if (type != fs::file_type::directory) {
        if (recorded)
            m_report["notes"].push_back(
                type == fs::file_type::symlink
                    ? "eval/: a symbolic link: not served"
                    : "eval/: not in the folder, though capture.json records the eval stage");
        return;
    }
    // The listing: regular files only (a link could lead anywhere), PNGs and metrics.json.
    size_t listed = 0;
    for (fs::directory_iterator it(eval, ec), end; !ec && it != end; it.increment(ec)) {
        if (++listed > k_max_eval_files) break;
        const std::string name = it->path().filename().string();
        std::error_code entry_ec;  // an entry gone since the listing is skipped, not an error
        if (!plain_name(name) || it->symlink_status(entry_ec).type() != fs::file_type::regular) continue;
        if (name == "metrics.json" || it->path().extension() == ".png")
            add_file("eval/" + name, content_type_of(name));
    }
    if (ec) throw Error(eval.string() + ": cannot list (" + ec.message() + ")");
    const fs::path metrics_file = eval / "metrics.json";
    if (!plain_file(metrics_file)) {
        m_report["notes"].push_back("eval/metrics.json: not in the folder (or not a regular file)");
        return;
    }
    const std::string mf = metrics_file.string();
    const nlohmann::json metrics = read_json_file(metrics_file);
    if (!metrics.is_object()) throw Error(mf + ": expected a JSON object (nerfpt eval's metrics)");
    const auto images = metrics.find("images");
    if (images == metrics.end() || !images->is_array()) throw Error(mf + ": 'images': expected an array");
    nlohmann::json views = nlohmann::json::array();
    for (size_t k = 0; k < images->size(); ++k) {
        const nlohmann::json& image = (*images)[k];
        const std::string where = mf + ": images[" + std::to_string(k) + "]";
        if (!image.is_object()) throw Error(where + ": expected an object");
        const auto n = image.find("name");
        if (n == image.end() || !n->is_string()) throw Error(where + ".name: expected a string");
        const std::string name = n->get<std::string>();
        if (!plain_name(name)) throw Error(where + ".name: '" + name + "' is not a file name in eval/");
        nlohmann::json v = {{"name", name},
                            {"psnr", metric(image, "psnr", where)},
                            {"ssim", metric(image, "ssim", where)},
                            {"frame", image.value("frame", nlohmann::json(nullptr))}};
        static const std::pair<const char*, const char*> k_kinds[] = {
            {"render", ".png"}, {"compare", "_compare.png"}, {"alpha", "_alpha.png"}};
        for (const auto& [key, suffix] : k_kinds) {
            const std::string file = name + suffix;
            v[key] = m_files.count("/capture/eval/" + file) ? nlohmann::json(url_of("eval/", file))
                                                            : nlohmann::json(nullptr);
        }
        views.push_back(std::move(v));
    }
    const nlohmann::json mean = metrics.value("mean", nlohmann::json::object());
    m_report["eval"] = {
        {"views", views.size()},
        {"psnr", mean.is_object() ? mean.value("psnr", nlohmann::json(nullptr)) : nlohmann::json(nullptr)},
        {"ssim", mean.is_object() ? mean.value("ssim", nlohmann::json(nullptr)) : nlohmann::json(nullptr)},
        {"width", metrics.value("width", nlohmann::json(nullptr))},
        {"height", metrics.value("height", nlohmann::json(nullptr))},
        {"metrics", url_of("eval/", "metrics.json")},
        {"images", std::move(views)}};
}

void CaptureReport::add_file(const std::string& name_under_dir, const std::string& content_type) {
    m_files[std::string(k_prefix) + name_under_dir] = ServedFile{content_type, {}, m_dir / name_under_dir};
}

std::vector<std::string> CaptureReport::paths() const {
    std::vector<std::string> p{std::string(k_report_path)};
    for (const auto& [path, file] : m_files) p.push_back(path);
    return p;
}

std::optional<ServedFile> CaptureReport::find(std::string_view path) const {
    if (path == k_report_path) return ServedFile{"application/json", m_report_text, {}};
    const auto it = m_files.find(path);
    if (it == m_files.end()) return std::nullopt;
    return it->second;
}

}  // namespace npt::serve
