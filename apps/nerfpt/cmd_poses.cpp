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

void add_poses_quality_option(CLI::App* cmd, std::string& quality, const std::string& prefix) {
    cmd->add_option("--poses-quality", quality,
                    prefix + "COLMAP's effort: fast, balanced or best (COLMAP's own settings); 'nerfpt poses "
                             "--help' says what each does")
        ->check(CLI::IsMember({"fast", "balanced", "best"}))
        ->capture_default_str();
}

void add_camera_model_option(CLI::App* cmd, std::string& model, const std::string& prefix) {
    cmd->add_option("--camera-model", model,
                    prefix + "COLMAP's lens model for the one camera all frames share: OPENCV (fx, fy, cx, cy, "
                             "k1, k2, p1, p2), RADIAL (one focal length f, cx, cy, k1, k2), SIMPLE_RADIAL (f, cx, "
                             "cy, k1), PINHOLE (fx, fy, cx, cy) or SIMPLE_PINHOLE (f, cx, cy); 'nerfpt poses "
                             "--help' says when to change it")
        ->check(CLI::IsMember({"OPENCV", "RADIAL", "SIMPLE_RADIAL", "PINHOLE", "SIMPLE_PINHOLE"}))
        ->capture_default_str();
}

CLI::App* add_poses_command(CLI::App& app, PosesArgs& args) {
    CLI::App* cmd = app.add_subcommand("poses", "Recover camera poses of frames with COLMAP; write transforms.json");
    // clang-format off
    cmd->footer(
        "Runs the colmap command-line tool (Debian: apt-get install colmap; CPU only) in a work folder:\n"
        "feature_extractor (one camera shared by all frames, --camera-model), the sequential matcher (frames of\n"
        "a video, in name order, each with its next 5 (fast) or 15) or the exhaustive one, and the mapper; keeps\n"
        "the reconstruction with the most frames (fast and balanced then close its loops: frames whose cameras\n"
        "revisit an earlier view, farther back than the sequential matcher reaches, are matched with it and the\n"
        "mapper runs again, then drop the observations that reproject more than twice the model's mean error and\n"
        "adjust it again), warns when the camera path leaps between neighbouring frames, and\n"
        "writes transforms.json as instant-ngp's colmap2nerf does: OpenGL cameras, the average camera up turned\n"
        "to +Z, the point the cameras look at moved to the origin, the mean camera distance scaled to 4,\n"
        "aabb_scale 16 (docs/formats.md). Fails without writing when fewer than --min-registered of the frames\n"
        "are registered.\n"
        "--poses-quality sets how much work COLMAP does (measured in docs/benchmarks.md, 'How fast COLMAP can\n"
        "be' and 'Every scale, fewer pairs'):\n"
        "  fast      (default) SIFT at the frame's own size (frames under 800 px are still doubled), every\n"
        "            scale level up to ~8000 features per megapixel, one orientation per keypoint; each frame\n"
        "            matched with its next 5; a global bundle adjustment only when the model has doubled,\n"
        "            with fewer iterations.\n"
        "  balanced  SIFT on the doubled frame as COLMAP does, at most ~2000 features per megapixel of it,\n"
        "            each frame matched with its next 15, bundle adjustments between fast's and best's.\n"
        "  best      COLMAP's own settings (up to 8192 features per frame, a global bundle adjustment every\n"
        "            10% of growth), each frame matched with its next 15: what nerfpt ran before the option\n"
        "            existed; slowest.\n"
        "Every quality passes --threads to each COLMAP step.\n"
        "--camera-model is the lens model COLMAP fits (one camera for all frames); transforms.json gets its\n"
        "fl_x, fl_y, cx, cy, k1, k2, p1, p2 (terms the model lacks are 0; a one-focal model writes fl_x = fl_y).\n"
        "OPENCV (default, as instant-ngp's colmap2nerf) fits fx and fy apart; RADIAL and SIMPLE_RADIAL fit one\n"
        "focal length, as a phone's square pixels have; the PINHOLE models assume no distortion. Measured on\n"
        "simulated handheld captures in docs/benchmarks.md ('One focal length or two').\n"
        "Example: nerfpt poses out/beer/frames -o out/beer/transforms.json");
    // clang-format on
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
    add_poses_quality_option(cmd, args.quality, "");
    add_camera_model_option(cmd, args.camera_model, "");
    cmd->add_option("--threads", args.threads, "COLMAP's threads for every step, 0 = all hardware threads")
        ->check(CLI::Range(0, 4096));
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
    s.quality = capture::parse_poses_quality(args.quality);
    s.threads = args.threads;
    s.camera_model = args.camera_model;
    const capture::ColmapRun run = capture::run_colmap(args.frames, work, s, [&](const std::string& step) {
        if (!global.quiet) fmt::print(stderr, "poses: COLMAP {} ...\n", step);
    });
    const size_t registered = run.model.images.size();
    const capture::ReprojectionStats rep = capture::reprojection_error(run.model);
    fmt::print("COLMAP registered {} of {} frames ({}), {} points, mean reprojection error {:.3f} px "
               "(--poses-quality {}, up to {} features per frame)\n",
               registered, run.frames, run.model_folder.string(), run.model.points.size(), rep.mean_px,
               args.quality, run.max_num_features);
    // CPU time beside wall time: on a shared machine only the first is comparable between runs.
    static const char* const k_steps[capture::k_colmap_steps] = {"extraction", "matching", "mapping", "loops",
                                                                 "refine"};
    if (!run.model.cameras.empty()) {
        const capture::ColmapCamera& c = run.model.cameras.front();
        const capture::Intrinsics k = c.intrinsics();
        fmt::print("  camera {} {}x{}: fx {:.2f}, fy {:.2f}, cx {:.2f}, cy {:.2f}, k1 {:.5f}, k2 {:.5f}, p1 {:.5f}, "
                   "p2 {:.5f}\n",
                   capture::camera_model_name(c.model), c.width, c.height, k.fx, k.fy, k.cx, k.cy, k.k1, k.k2,
                   k.p1, k.p2);
    }
    if (!run.refine_skipped.empty())
        spdlog::warn("the poses are the unrefined model's: {}", run.refine_skipped);
    for (int i = 0; i < capture::k_colmap_steps; ++i) {
        if (i == 3 && run.loop_pairs == 0) continue;  // no loop closure: nothing revisited, or not asked for
        if (i == 4 && run.refine_threshold_px == 0) continue;  // not run (best), or its model was not kept
        std::string what;
        if (i == 3) what = fmt::format(": {} revisiting pairs matched, mapped again", run.loop_pairs);
        if (i == 4)
            what = fmt::format(
                ": observations over {:.2f} px dropped, adjusted again (mean error {:.3f} -> {:.3f} px)",
                run.refine_threshold_px, run.refine_error_before_px, run.refine_error_after_px);
        fmt::print("  {:<10} {:6.1f} s wall, {:6.1f} s CPU (load {:.2f} at start){}\n", k_steps[i],
                   run.seconds[i], run.cpu_seconds[i], run.load_at_start[i], what);
    }
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
    summary.loop_pairs = run.loop_pairs;
    summary.refine_threshold_px = run.refine_threshold_px;
    static_assert(capture::k_colmap_steps == sizeof(summary.seconds) / sizeof(summary.seconds[0]));
    for (int i = 0; i < capture::k_colmap_steps; ++i) {
        summary.seconds[i] = run.seconds[i];
        summary.cpu_seconds[i] = run.cpu_seconds[i];
    }
    summary.max_num_features = run.max_num_features;
    summary.model_folder = run.model_folder.string();
    return summary;
}

}  // namespace npt::cli
