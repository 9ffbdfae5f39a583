#include "capture_record.h"

#include <fmt/format.h>

#include "capture/capture_summary.h"
#include "core/error.h"
#include "core/json_file.h"
#include "core/temp_file.h"

namespace npt::cli {
namespace fs = std::filesystem;

namespace {

constexpr int k_record_version = 1;

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
    for (const char* name : capture::k_capture_stages) {
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
    std::string md = fmt::format("# nerfpt capture of {}\n\n", record.value("video", "?"));
    md += "| stage | result | time |\n|---|---|---|\n";
    const std::vector<capture::CaptureStageRow> rows = capture::capture_stage_rows(record);
    for (const capture::CaptureStageRow& r : rows)
        md += fmt::format("| {} | {} |{}|\n", r.label, r.result, r.time.empty() ? " " : " " + r.time + " ");
    md += fmt::format(
        "\nTotal: {:.1f} s. The model is model.npt; `nerfpt info model.npt` says where its content "
        "lies, to place it in a scene.\n",
        capture::capture_total_seconds(rows));
    return md;
}

}  // namespace npt::cli
