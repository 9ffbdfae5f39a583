#include "cmd_curate.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstdlib>
#include <iostream>
#include <optional>
#include <sstream>
#include <vector>

#include "capture/curate.h"
#include "core/error.h"
#include "core/progress.h"

namespace npt::cli {
namespace {

// "H,S,V" -> three numbers; `option` names the flag in the error.
void parse_hsv(const std::string& text, const char* option, float& h, float& s, float& v) {
    std::vector<float> values;
    std::stringstream in(text);
    std::string part;
    while (std::getline(in, part, ',')) {
        char* end = nullptr;
        const float x = std::strtof(part.c_str(), &end);
        if (part.empty() || end == part.c_str() || *end != '\0')
            values.push_back(-1e30f);
        else
            values.push_back(x);
    }
    if (values.size() != 3 || values[0] == -1e30f || values[1] == -1e30f || values[2] == -1e30f) {
        throw Error(fmt::format("curate: {} must be three numbers H,S,V (got '{}')", option, text));
    }
    h = values[0];
    s = values[1];
    v = values[2];
}

}  // namespace

CLI::App* add_curate_command(CLI::App& app, CurateArgs& args) {
    CLI::App* cmd =
        app.add_subcommand("curate", "Pick the sharp, subject-centred frames of a video for COLMAP");
    cmd->footer(
        "Decodes VIDEO with the ffmpeg command-line tool (phone rotation applied), scores every decoded "
        "frame\n"
        "and writes the kept ones to FRAMES_DIR/frame_NNNNN.png (NNNNN = frame number in the video), plus\n"
        "curate.json (score and verdict per frame) and contact_sheet.png (kept framed green, dropped red).\n"
        "Rules, in order:\n"
        "  subject: an HSV mask (--hsv-min/--hsv-max; H in degrees 0-360, S and V 0-1; default automatic:\n"
        "    the median HSV of the more saturated half of the central 10% of the first frame, +-20 deg\n"
        "    hue, +-0.25 S and V); a frame\n"
        "    whose largest blob's centroid lies more than 8 sigma from the median centroid (sigma from the\n"
        "    median absolute deviation, at least 1% of the frame) is dropped.\n"
        "  sharpness: variance of the Laplacian of the grey image (longest side 480).\n"
        "    window (default): split the video into --target-frames equal time windows, keep the sharpest\n"
        "      frame of each, unless it is below mean - 2 sigma of all scores. Uniform coverage around the\n"
        "      object is what COLMAP's sequential matcher needs.\n"
        "    threshold: keep every frame at or above mean - 1 sigma (the design paper's rule).\n"
        "Fields of curate.json: docs/formats.md, 'curate'.\n"
        "Example: nerfpt curate Beer.mp4 -o beer/frames --max-frames 300 --target-frames 100");
    cmd->add_option("VIDEO", args.video, "Video file (anything ffmpeg decodes)")->required();
    cmd->add_option("-o,--output", args.output, "Folder for the kept frames and the report")->required();
    cmd->add_option("--max-frames", args.max_frames, "Decode at most N frames, evenly spread (0: all)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--target-frames", args.target_frames, "Window rule: number of time windows")
        ->capture_default_str();
    cmd->add_option("--rule", args.rule, "Sharpness rule")
        ->check(CLI::IsMember({"window", "threshold"}))
        ->capture_default_str();
    auto* hmin = cmd->add_option("--hsv-min", args.hsv_min, "Subject colour, lower bound H,S,V");
    auto* hmax = cmd->add_option("--hsv-max", args.hsv_max, "Subject colour, upper bound H,S,V");
    hmin->needs(hmax);
    hmax->needs(hmin);
    return cmd;
}

int run_curate(const CurateArgs& args, const GlobalSettings& global) {
    curate_stage(args, global);
    return 0;
}

capture::CurateReport curate_stage(const CurateArgs& args, const GlobalSettings& global) {
    capture::CurateSettings settings;
    settings.max_frames = args.max_frames;
    settings.target_frames = args.target_frames;
    settings.rule =
        args.rule == "threshold" ? capture::SharpnessRule::Threshold : capture::SharpnessRule::Window;
    if (!args.hsv_min.empty()) {
        capture::HsvRange r;
        parse_hsv(args.hsv_min, "--hsv-min", r.h_min, r.s_min, r.v_min);
        parse_hsv(args.hsv_max, "--hsv-max", r.h_max, r.s_max, r.v_max);
        settings.hsv = r;
    }
    capture::validate_settings(settings);

    ProgressSettings decode_ps;
    decode_ps.label = "decode";
    decode_ps.unit = "frames";
    decode_ps.style = progress_style(stream_is_tty(stderr), global.quiet);
    ProgressSettings write_ps = decode_ps;
    write_ps.label = "write";
    Progress decode_progress(decode_ps, std::cerr);
    // Made when writing starts, so that its clock and rate cover the writing only.
    std::optional<Progress> write_progress;
    const capture::CurateReport report = capture::curate_video(
        args.video, args.output, settings,
        [&](uint64_t done, uint64_t total) { decode_progress.update(done, total); },
        [&](uint64_t done, uint64_t total) {
            if (!write_progress) {
                decode_progress.finish();
                write_progress.emplace(write_ps, std::cerr);
            }
            write_progress->update(done, total);
        });
    decode_progress.finish();
    if (write_progress) write_progress->finish();
    spdlog::info(
        "sharpness mean {:.1f}, sigma {:.1f}; subject centroid ({:.0f}, {:.0f}) +- ({:.0f}, {:.0f}) px",
        report.sharp.mean, report.sharp.stddev, report.centroid_centre.x, report.centroid_centre.y,
        report.centroid_sigma.x, report.centroid_sigma.y);
    fmt::print("kept {} of {} decoded frames ({} in the video) in {:.1f} s; wrote {}/curate.json\n",
               report.kept, report.frames.size(), report.info.frame_count, report.seconds, args.output);
    return report;
}

}  // namespace npt::cli
