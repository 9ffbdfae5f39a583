// capture.json: what each stage of `nerfpt capture` produced, written after every stage. It is both the
// machine-readable report and the state that lets a second run skip the stages that are done. report.md is
// the same facts for a person.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace npt::cli {

class CaptureRecord {
  public:
    // Loads WORKDIR/capture.json when it exists. Throws npt::Error naming the file when it is unreadable or
    // records a different video (a work folder holds one capture).
    CaptureRecord(const std::filesystem::path& workdir, const std::filesystem::path& video);

    bool done(const std::string& stage) const;
    const nlohmann::json& stage(const std::string& name) const;
    // Records the stage's result and writes capture.json and report.md (atomically).
    void finish(const std::string& stage, nlohmann::json result);
    // Drops `stage` and every later one (curate, poses, object, split, train, eval, turntable) and saves: their
    // results no longer hold once an earlier output changes.
    void forget_from(const std::string& stage);
    std::string markdown() const;

    const std::filesystem::path& path() const { return m_path; }

  private:
    void save() const;

    std::filesystem::path m_workdir, m_path;
    nlohmann::json m_json;
};

// report.md from a capture.json object; exposed for tests.
std::string capture_report_markdown(const nlohmann::json& record);

}  // namespace npt::cli
