// `nerfpt serve CAPTURE_DIR`: a capture's folder (what `nerfpt capture VIDEO -o DIR` writes) read once at the
// start: its model, the object frame capture.json records, and the report page's data (/capture/report.json)
// and files (eval's images and metrics, the turntable video, report.md). Those files are served from an
// allow-list made here, of regular files (no symbolic links) inside the folder: a URL is only ever compared
// with that list, never joined to a path.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "nerf/object_frame.h"
#include "serve/page_io.h"

namespace npt::serve {

class CaptureReport final : public RouteSource {
  public:
    // Reads DIR/capture.json and DIR/eval/metrics.json and lists DIR/eval. Throws npt::Error, one line naming
    // the file and the field: no capture.json, malformed JSON or fields, an unfinished capture without
    // model.npt (saying which stage is not recorded), a file name in them that is not a plain name.
    explicit CaptureReport(const std::filesystem::path& dir);

    const std::filesystem::path& dir() const { return m_dir; }
    const std::filesystem::path& model() const { return m_model; }
    // stages.object.model_frame when the object stage found the object (the frame model.npt carries).
    const std::optional<nerf::ObjectFrame>& object_frame() const { return m_frame; }
    // The capture's median camera elevation (stages.turntable.elevation_deg), when recorded.
    std::optional<double> elevation_deg() const { return m_elevation_deg; }
    // /capture/report.json (docs/formats.md, "nerfpt serve CAPTURE_DIR").
    const nlohmann::json& report() const { return m_report; }
    // Its URL paths, decoded: "/capture/report.json", "/capture/eval/r_0_compare.png", ...
    std::vector<std::string> paths() const;

    std::optional<ServedFile> find(std::string_view path) const override;

    static constexpr std::string_view k_report_path = "/capture/report.json";

  private:
    void read_eval(const nlohmann::json& stages);
    void add_file(const std::string& name_under_dir, const std::string& content_type);

    std::filesystem::path m_dir, m_model;
    std::optional<nerf::ObjectFrame> m_frame;
    std::optional<double> m_elevation_deg;
    nlohmann::json m_report;
    std::string m_report_text;
    std::map<std::string, ServedFile, std::less<>> m_files;  // decoded URL path -> file
};

}  // namespace npt::serve
