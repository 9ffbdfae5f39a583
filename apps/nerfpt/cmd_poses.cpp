#include "cmd_poses.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <filesystem>

#include "capture/colmap_runner.h"
#include "capture/path_continuity.h"
#include "capture/transforms_writer.h"
#include "core/error.h"
#include "interrupt.h"

namespace npt::cli {
namespace fs = std::filesystem;

CLI::App* add_poses_command(CLI::App& app, PosesArgs& args) {
    CLI::App* cmd = app.add_subcommand("poses", "Recover camera poses of frames with COLMAP; write transforms.json");
    cmd->footer(
        "Runs the colmap command-line tool (Debian: apt-get install colmap; CPU only) in a work folder:\n"
        "feature_extractor (one OPENCV camera shared by all frames), the sequential matcher (frames of a video,\n"
        "in name order, each with its next 15) or the exhaustive one, and the mapper; keeps the reconstruction\n"
        "with the most frames, warns when the camera path leaps between neighbouring frames, and\n"
        "writes transforms.json as instant-ngp's colmap2nerf does: OpenGL cameras, the average camera up turned\n"
        "to +Z, the point the cameras look at moved to the origin, the mean camera distance scaled to 4,\n"
        "aabb_scale 16 (docs/formats.md). Fails without writing when fewer than --min-registered of the frames\n"
        "are registered.\n"
        "Example: nerfpt poses out/beer/frames -o out/beer/transforms.json");
    cmd->add_option("FRAMES", args.frames, "Folder of frames (.png/.jpg), e.g. written by 'nerfpt curate'")
        ->required();
    cmd->add_option("-o,--output", args.output, "transforms.json to write; its folder must exist")->required();
    cmd->add_option("--work", args.work, "COLMAP's work folder (default: colmap/ beside the output)");
    cmd->add_option("--matcher", args.matcher, "sequential (video frames) or exhaustive (default: sequential)")
        ->check(CLI::IsMember({"sequential", "exhaustive"}));
    cmd->add_option("--aabb-scale", args.aabb_scale,
                    "instant-ngp's scene extent in unit cubes, a power of two 1..128 (default: 16)")
        ->check(CLI::IsMember({1, 2, 4, 8, 16, 32, 64, 128}));
    cmd->add_option("--max-image-size", args.max_image_size,
                    "Longest side COLMAP extracts features at, 256..8192 (default: 1600)")
        ->check(CLI::Range(256, 8192));
    cmd->add_option("--min-registered", args.min_registered,
                    "Fraction of the frames that must be registered, 0..1 (default: 0.5)")
        ->check(CLI::Range(0.0, 1.0));
    return cmd;
}

int run_poses(const PosesArgs& args, const GlobalSettings& global, InterruptGuard& interrupts) {
    poses_stage(args, global, interrupts);
    return 0;
}

PosesSummary poses_stage(const PosesArgs& args, const GlobalSettings& global, InterruptGuard& interrupts) {
    const fs::path out = args.output;
    const fs::path out_dir = out.parent_path().empty() ? fs::path(".") : out.parent_path();
    std::error_code ec;
    if (!fs::is_directory(out_dir, ec))
        throw Error("--output '" + out.string() + "': folder '" + out_dir.string() + "' does not exist");
    const fs::path work = args.work.empty() ? out_dir / "colmap" : fs::path(args.work);
    capture::ColmapSettings s;
    s.matcher = args.matcher;
    s.max_image_size = args.max_image_size;
    const capture::ColmapRun run = capture::run_colmap(args.frames, work, s, [&](const std::string& step) {
        if (!global.quiet) fmt::print(stderr, "poses: COLMAP {} ...\n", step);
    });
    const size_t registered = run.model.images.size();
    const capture::ReprojectionStats rep = capture::reprojection_error(run.model);
    fmt::print("COLMAP registered {} of {} frames ({}), {} points, mean reprojection error {:.3f} px; "
               "extraction {:.0f} s, matching {:.0f} s, mapping {:.0f} s\n",
               registered, run.frames, run.model_folder.string(), run.model.points.size(), rep.mean_px,
               run.seconds[0], run.seconds[1], run.seconds[2]);
    if (double(registered) < args.min_registered * double(run.frames) || registered < 3)
        throw Error(fmt::format(
            "COLMAP registered only {} of {} frames (--min-registered {}): try --matcher exhaustive, curate "
            "more or sharper frames (nerfpt curate --target-frames), or film with more overlap; the model is in {}",
            registered, run.frames, args.min_registered, run.model_folder.string()));
    // Poses from a video must form a path; a leap between neighbouring frames is a misplaced piece.
    const std::vector<capture::PathJump> jumps = capture::find_path_jumps(run.model);
    if (!jumps.empty()) {
        std::string list;
        for (size_t i = 0; i < jumps.size() && i < 4; ++i)
            list += fmt::format("{}{} -> {} ({:.0f}x the median step)", i ? ", " : "", jumps[i].from, jumps[i].to,
                                jumps[i].ratio);
        spdlog::warn("the camera path jumps {} time{} between neighbouring frames: {}{}. For frames of one video "
                     "this means COLMAP matched look-alike views from different sides (a symmetric object, a "
                     "repeating floor) and placed part of the video wrongly; keep --matcher sequential (it "
                     "matches neighbouring frames only), curate more frames (--target-frames) so that "
                     "neighbours overlap more, or film more of the surroundings",
                     jumps.size(), jumps.size() == 1 ? "" : "s", list, jumps.size() > 4 ? ", ..." : "");
    }
    capture::TransformsSettings ts;
    ts.images_folder = fs::absolute(args.frames);
    ts.aabb_scale = args.aabb_scale;
    {
        auto no_interrupt = interrupts.hold();
        capture::write_transforms(run.model, out, ts);
    }
    fmt::print("wrote {}\n", out.string());
    PosesSummary summary;
    summary.frames = run.frames;
    summary.registered = registered;
    summary.points = run.model.points.size();
    summary.reprojection_px = rep.mean_px;
    summary.path_jumps = jumps.size();
    for (int i = 0; i < 3; ++i) summary.seconds[i] = run.seconds[i];
    return summary;
}

}  // namespace npt::cli
