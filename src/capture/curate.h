// The curate stage: video -> the frames worth giving to COLMAP. Decodes (frame_source.h), scores each frame
// for blur (sharpness.h) and subject position (subject_mask.h), selects, and writes the kept frames, a
// curate.json report and a contact sheet. The format of curate.json is in docs/formats.md, "curate".
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "capture/frame_source.h"
#include "capture/sharpness.h"
#include "capture/subject_mask.h"

namespace npt::capture {

struct CurateSettings {
    int64_t max_frames = 0;   // decode at most this many, evenly spread over the video; 0: every frame
    int target_frames = 100;  // Window rule: number of time windows (at most one frame kept per window)
    SharpnessRule rule = SharpnessRule::Window;
    std::optional<HsvRange> hsv;  // none: automatic from the centre of the first decoded frame
    int analysis_side = 480;      // longest side of the copy that sharpness and mask are computed on
    int thumb_side = 120;         // longest side of a contact-sheet thumbnail
};

// Throws npt::Error (one line, naming the option) for unusable settings.
void validate_settings(const CurateSettings& s);

struct FrameRecord {
    int64_t index = 0;  // frame number in the video
    double time = 0.0;  // seconds
    double sharpness = 0.0;
    std::optional<Vec2> centroid;  // full-resolution pixels
    bool kept = false;
    std::string reason;  // why dropped; empty when kept
};

struct CurateReport {
    VideoInfo info;
    std::vector<FrameRecord> frames;
    HsvRange hsv;
    bool hsv_automatic = false;
    Selection sharp;  // mean/stddev of the scores
    Vec2 centroid_centre, centroid_sigma;
    int kept = 0;
    double seconds = 0.0;
};

// Applies the subject rule, then the sharpness rule among the frames that passed it; fills kept/reason.
// `frame_side` (longest side in pixels) sets the centroid sigma floor at 1% of it.
void apply_rules(CurateReport& report, const CurateSettings& settings, int frame_side);

using ProgressFn = std::function<void(uint64_t done, uint64_t total)>;

// The whole stage. Writes OUT/frame_NNNNN.png (NNNNN = frame number in the video, original resolution),
// OUT/curate.json and OUT/contact_sheet.png; old frame_*.png files in OUT are removed first so that a
// second run never leaves a mix. `on_decode` is called during the analysis pass, `on_write` while the kept
// frames are decoded again and written (keeping every full frame in memory would need gigabytes).
CurateReport curate_video(const std::filesystem::path& video, const std::filesystem::path& out_dir,
                          const CurateSettings& settings, const ProgressFn& on_decode = {},
                          const ProgressFn& on_write = {});

// Writers, exposed for tests.
void write_curate_json(const std::filesystem::path& path, const std::filesystem::path& video,
                       const CurateReport& report, const CurateSettings& settings);
void write_rgb8_png(const std::filesystem::path& path, const Frame8& frame);
// Thumbnail by box filter, longest side at most `side`.
Frame8 thumbnail(const Frame8& frame, int side);
// Thumbnails in a grid, each framed green (kept) or red (dropped).
Frame8 contact_sheet(const std::vector<Frame8>& thumbs, const std::vector<bool>& kept);

}  // namespace npt::capture
