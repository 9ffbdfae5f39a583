// One line per finished stage of `nerfpt capture` from its capture.json (docs/formats.md, "A whole capture"):
// what the stage produced and how long it took. report.md is these rows as a Markdown table; `nerfpt serve
// CAPTURE_DIR`'s report page shows the same rows, so that the two never tell different facts.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

namespace npt::capture {

// The stages in the order they run (capture.json's `stages` keys).
inline constexpr const char* k_capture_stages[] = {"curate", "poses", "object",  "split",
                                                   "train",  "eval",  "isolate", "turntable"};

struct CaptureStageRow {
    std::string stage;   // the capture.json key ("eval")
    std::string label;   // report.md's first column ("held-out views")
    std::string result;  // what it produced, one line
    std::string time;    // "12.3 s", with the parts of the poses stage; "" for an untimed stage
    double seconds = 0;  // the stage's `seconds`, when timed
    bool timed = false;
    bool counted =
        false;  // added to the total (the object stage's time is shown but, as report.md has it, not)
};

// The rows of the stages recorded in `record` (capture.json's whole object), in stage order. Fields missing
// or of another type read as 0 or "": the record is the capture's own output.
std::vector<CaptureStageRow> capture_stage_rows(const nlohmann::json& record);
// The sum of the rows' times that report.md's "Total" adds.
double capture_total_seconds(const std::vector<CaptureStageRow>& rows);

}  // namespace npt::capture
