#include "cmd_capture.h"

#include "backend_option.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <vector>

#include "capture/camera_rig.h"
#include "capture/frame_source.h"
#include "capture/transforms_split.h"
#include "capture_record.h"
#include "cmd_curate.h"
#include "cmd_eval.h"
#include "cmd_poses.h"
#include "cmd_train.h"
#include "cmd_view.h"
#include "core/error.h"
#include "core/executable.h"
#include "core/json_file.h"
#include "input_checks.h"
#include "interrupt.h"
#include "nerf/model_file.h"
#include "nerf/object_isolation.h"
#include "object_stage.h"

namespace npt::cli {
namespace fs = std::filesystem;

namespace {

// Automatic --downscale: the training images' longest side at most this. A few minutes of CPU training
// cannot resolve more detail, and smaller images load faster and take less memory. 480 (was 400): with half
// the rays on the object, a 540x960 capture's object is sharper at 270x480 than at 180x320 at every size it
// was scored (docs/benchmarks.md, "Training rays on the object").
constexpr int k_auto_train_side = 480;
constexpr int k_stages = 8;
const char* const k_stage_names[k_stages] = {"curate", "poses", "object",  "split",
                                             "train",  "eval",  "isolate", "turntable"};

// What `--force` removes: only what capture itself writes, never the whole folder.
const std::vector<std::string> k_outputs = {
    "frames",    "colmap", "transforms.json", "transforms_train.json", "transforms_test.json",
    "model.npt", "model_scene.npt", "eval", "turntable.mp4", "capture.json", "report.md"};

class Clock {
  public:
    double seconds() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
    }

  private:
    std::chrono::steady_clock::time_point m_start = std::chrono::steady_clock::now();
};

void banner(const GlobalSettings& global, int k, const std::string& text) {
    if (global.quiet) return;
    std::fflush(stdout);  // the stages print results on stdout: keep them in order with these lines
    fmt::print(stderr, "capture [{}/{}] {}\n", k, k_stages, text);
}

void require_tools() {
    std::vector<std::string> missing;
    for (const char* tool : {"ffmpeg", "ffprobe", "colmap"})
        if (find_executable(tool).empty()) missing.push_back(tool);
    if (!missing.empty())
        throw Error(
            fmt::format("{} not found on PATH: nerfpt capture needs them (Debian: apt-get install ffmpeg "
                        "colmap)",
                        fmt::join(missing, ", ")));
}

int auto_downscale(int width, int height) {
    const int side = std::max(width, height);
    return std::max(1, (side + k_auto_train_side - 1) / k_auto_train_side);
}

// A stage before training that runs again (new frames, poses or split) makes the model and what was rendered
// from it stale: they go, so that training starts over instead of resuming a model of other data.
void discard_trained(const fs::path& work, CaptureRecord& record) {
    for (const char* name : {"model.npt", "model_scene.npt", "eval", "turntable.mp4"}) {
        std::error_code ec;
        fs::remove_all(work / name, ec);
        if (ec) throw Error((work / name).string() + ": cannot remove (" + ec.message() + ")");
    }
    record.forget_from("train");
}

}  // namespace

CLI::App* add_capture_command(CLI::App& app, CaptureArgs& args) {
    CLI::App* cmd =
        app.add_subcommand("capture", "A phone video to a trained NeRF: curate, poses, train, report");
    cmd->footer(
        "Runs, in WORKDIR:\n"
        "  1 curate     VIDEO -> frames/ (nerfpt curate: sharpest frame per time window, subject check)\n"
        "  2 poses      frames/ -> transforms.json (nerfpt poses: COLMAP, one shared camera, --camera-model)\n"
        "  3 object     the supporting plane, up and the object's box from COLMAP's points -> the object frame\n"
        "               the model carries (origin at the base centre, +Z up; metres with --height)\n"
        "  4 split      every --holdout-every'th frame -> transforms_test.json, the rest -> "
        "transforms_train.json\n"
        "  5 train      -> model.npt (nerfpt train on the training frames, --train-time seconds; with\n"
        "                  --relightable also the relight stage)\n"
        "  6 eval       PSNR/SSIM on the held-out frames -> eval/ (renders, comparisons, metrics.json)\n"
        "  7 isolate    when stage 3 found the object: model.npt keeps only it (nerfpt isolate: its box, above\n"
        "                  the supporting plane, no floaters); --keep-scene keeps the whole scene as\n"
        "                  model_scene.npt, which further training then continues (else it continues the\n"
        "                  object's model, whose occupancy grid grows back where the network has density)\n"
        "  8 turntable  -> turntable.mp4, an orbit at the capture's camera distance, height and field of "
        "view;\n"
        "                  the object alone (its box) when stage 3 found it\n"
        "and writes capture.json (every stage's numbers) and report.md after each stage. Run the same "
        "command\n"
        "again after an error or Ctrl-C and it continues with the first unfinished stage (training resumes "
        "from\n"
        "its last checkpoint); a larger --train-time continues training and redoes eval and turntable, "
        "another\n"
        "--holdout-every redoes the split and retrains; curate and poses options take effect with --force,\n"
        "which starts over. Needs ffmpeg and colmap on PATH (Debian: apt-get install ffmpeg colmap).\n"
        "With --serve, a page in the browser lists the stages and their times as they finish and shows the\n"
        "training live (loss, held-out PSNR, truth | render | error); it stays up after the capture until Ctrl-C.\n"
        "Example: nerfpt capture Beer.mp4 -o beer --train-time 600");
    cmd->add_option("VIDEO", args.video, "Video walking around the object (anything ffmpeg decodes)")
        ->required();
    cmd->add_option("-o,--output", args.output, "Work folder (created if missing)")->required();
    cmd->add_option("--target-frames", args.target_frames, "curate: frames to keep, one per time window")
        ->check(CLI::Range(3, 100000))
        ->capture_default_str();
    cmd->add_option("--max-frames", args.max_frames,
                    "curate: decode at most N frames, evenly spread (0: all)")
        ->check(CLI::NonNegativeNumber);
    auto* hmin = cmd->add_option("--hsv-min", args.hsv_min, "curate: subject colour, lower bound H,S,V");
    auto* hmax = cmd->add_option("--hsv-max", args.hsv_max, "curate: subject colour, upper bound H,S,V");
    hmin->needs(hmax);
    hmax->needs(hmin);
    cmd->add_option("--matcher", args.matcher, "poses: sequential (video order) or exhaustive")
        ->check(CLI::IsMember({"sequential", "exhaustive"}))
        ->capture_default_str();
    add_poses_quality_option(cmd, args.poses_quality, "poses: ");
    add_camera_model_option(cmd, args.camera_model, "poses: ");
    cmd->add_option("--aabb-scale", args.aabb_scale, "poses: instant-ngp's scene extent in unit cubes")
        ->check(CLI::IsMember({1, 2, 4, 8, 16, 32, 64, 128}))
        ->capture_default_str();
    cmd->add_option("--min-registered", args.min_registered,
                    "poses: fraction of the frames COLMAP must register, 0..1")
        ->check(CLI::Range(0.0, 1.0))
        ->capture_default_str();
    cmd->add_option("--height", args.height_m,
                    "object: the object's real height in metres: the model stands at real size (default: the "
                    "capture's units)")
        ->check(CLI::Range(1e-4, 1e4));
    cmd->add_option("--holdout-every", args.holdout_every,
                    "Hold out every Nth frame for the PSNR report, 2..1000; 0: train on all, no PSNR")
        ->check(CLI::Range(0, 1000))
        ->capture_default_str();
    cmd->add_option("--train-time", args.train_seconds, "train: seconds of training in total")
        ->check(CLI::Range(1.0, 1e7))
        ->capture_default_str();
    cmd->add_option("--train-steps", args.train_steps, "train: steps in total instead of --train-time")
        ->check(CLI::Range(uint64_t(1), uint64_t(100000000)));
    cmd->add_option("--downscale", args.downscale,
                    fmt::format("train/eval: shrink the frames by this factor (0: automatic, longest side at "
                                "most {} px)",
                                k_auto_train_side))
        ->check(CLI::Range(0, 64))
        ->capture_default_str();
    cmd->add_option("--config", args.config, "train: JSON model and training settings (docs/formats.md)");
    cmd->add_flag("--relightable", args.relightable,
                  "train: also fit albedo, roughness and normals and estimate the capture light, so that scenes "
                  "light the object with their own lights (nerfpt train --relightable; docs/relighting.md). Added "
                  "to a capture trained without it, it runs only that stage");
    cmd->add_option("--relight-steps", args.relight_steps,
                    fmt::format("train: optimiser steps of the relight stage (default: {})", args.relight_steps))
        ->check(CLI::Range(uint64_t(1), uint64_t(10000000)));
    cmd->add_option("--relight-points", args.relight_points,
                    fmt::format("train: surface points of the relight stage (default: {} on a GPU, {} on the CPU)",
                                k_relight_points_gpu, k_relight_points_cpu))
        ->check(CLI::Range(64, 1 << 22));
    cmd->add_option("--relight-pixels", args.relight_pixels,
                    fmt::format("train: pixels of the relight stage that borrow a surface point's light "
                                "(default: {} on a GPU, {} on the CPU)",
                                k_relight_pixels_gpu, k_relight_pixels_cpu))
        ->check(CLI::Range(0, 1 << 24));
    cmd->add_option("--turntable-frames", args.turntable_frames, "Frames of the turntable video (0: none)")
        ->check(CLI::Range(0, 100000))
        ->capture_default_str();
    cmd->add_option("--turntable-res", args.turntable_res,
                    "WIDTHxHEIGHT of the turntable (default: the training size)");
    cmd->add_flag("--keep-scene", args.keep_scene,
                  "isolate: keep the whole-scene model (the room, the table) as model_scene.npt beside the "
                  "object's model.npt");
    add_backend_option(cmd, args.backend);
    cmd->add_option("--threads", args.threads, "Worker threads, 0 = all hardware threads")
        ->check(CLI::Range(0, 4096));
    cmd->add_flag("--force", args.force,
                  "Remove what an earlier capture wrote in the work folder, start over");
    add_live_serve_options(cmd, args.serve);
    return cmd;
}

int run_capture(const CaptureArgs& args, const GlobalSettings& global, InterruptGuard& interrupts) {
    check_requested_backend(args.backend);
    require_file(args.video, "VIDEO");
    require_tools();
    if (args.holdout_every == 1) throw Error("--holdout-every 1 would hold out every frame: use 0 or >= 2");
    if (!args.config.empty()) require_file(args.config, "--config");
    // Resolved once, when the first stage that uses it starts (--backend cuda without a GPU fails there, and
    // the CPU fallback's note is shown once).
    std::string resolved_backend;
    auto backend = [&] {
        if (resolved_backend.empty()) resolved_backend = nerf::backend_name(resolve_backend(args.backend));
        return resolved_backend;
    };
    // A file ffmpeg cannot read fails here, before the work folder is made.
    const capture::VideoInfo info = capture::probe_video(args.video);
    spdlog::debug("{}: {}x{}, {} frames at {:.2f} fps", args.video, info.width, info.height, info.frame_count,
                  info.fps);
    const fs::path work = args.output;
    prepare_output_folder(work, "--output");
    if (args.force) {
        for (const std::string& name : k_outputs) {
            std::error_code ec;
            fs::remove_all(work / name, ec);
            if (ec) throw Error((work / name).string() + ": cannot remove (" + ec.message() + ")");
        }
    }
    CaptureRecord record(work, args.video);
    // --serve: the page lists the stages as they run and finish, and shows the training live.
    std::unique_ptr<LiveTraining> live;
    if (args.serve.enabled) live = std::make_unique<LiveTraining>(args.serve, "nerfpt capture " + args.video);
    std::vector<std::string> stage_notes(k_stages);
    auto publish_stages = [&](int running) {
        if (!live) return;
        nlohmann::json list = nlohmann::json::array();
        for (int i = 0; i < k_stages; ++i) {
            const std::string name = k_stage_names[size_t(i)];
            const bool done = record.done(name);
            const std::string state = i + 1 < running   ? (done ? "done" : "skipped")
                                      : i + 1 == running ? "running"
                                                         : (done ? "done" : "pending");
            const nlohmann::json& r = record.stage(name);
            list.push_back({{"name", name},
                            {"state", state},
                            {"note", stage_notes[size_t(i)]},
                            {"seconds", r.contains("seconds") ? r["seconds"] : nlohmann::json(nullptr)}});
        }
        live->monitor().set_stages(std::move(list));
        live->monitor().set_phase(running <= k_stages ? "capture: " + stage_notes[size_t(running - 1)]
                                                       : "capture finished");
    };
    auto stage = [&](int k, const std::string& text) {
        banner(global, k, text);
        stage_notes[size_t(k - 1)] = text;
        publish_stages(k);
    };
    const fs::path frames = work / "frames", transforms = work / "transforms.json",
                   model = work / "model.npt", scene_model = work / "model_scene.npt";
    const std::string continue_hint =
        fmt::format("the same 'nerfpt capture {} -o {} ...' command", args.video, args.output);

    // 1 curate
    if (record.done("curate")) {
        stage(1, "curate: done in an earlier run (frames/)");
    } else {
        stage(1, "curate: choosing frames");
        record.forget_from("poses");  // new frames: every later stage runs again
        discard_trained(work, record);
        CurateArgs c;
        c.video = args.video;
        c.output = frames.string();
        c.max_frames = args.max_frames;
        c.target_frames = args.target_frames;
        c.hsv_min = args.hsv_min;
        c.hsv_max = args.hsv_max;
        const capture::CurateReport r = curate_stage(c, global);
        record.finish("curate", {{"kept", r.kept},
                                 {"decoded", r.frames.size()},
                                 {"video_frames", r.info.frame_count},
                                 {"video_width", r.info.width},
                                 {"video_height", r.info.height},
                                 {"fps", r.info.fps},
                                 {"seconds", r.seconds}});
    }

    // 2 poses
    if (record.done("poses")) {
        stage(2, "poses: done in an earlier run (transforms.json)");
    } else {
        stage(2, "poses: COLMAP");
        record.forget_from("object");
        discard_trained(work, record);
        PosesArgs p;
        p.frames = frames.string();
        p.output = transforms.string();
        p.work = (work / "colmap").string();
        p.matcher = args.matcher;
        p.quality = args.poses_quality;
        p.camera_model = args.camera_model;
        p.threads = args.threads;
        p.aabb_scale = args.aabb_scale;
        p.min_registered = args.min_registered;
        const Clock clock;
        const PosesSummary s = poses_stage(p, global, interrupts);
        record.finish("poses", {{"quality", args.poses_quality},
                                {"camera_model", args.camera_model},
                                {"max_num_features", s.max_num_features},
                                {"frames", s.frames},
                                {"registered", s.registered},
                                {"points", s.points},
                                {"reprojection_px", s.reprojection_px},
                                {"path_jumps", s.path_jumps},
                                {"extraction_seconds", s.seconds[0]},
                                {"matching_seconds", s.seconds[1]},
                                {"mapping_seconds", s.seconds[2]},
                                {"loop_closure_seconds", s.seconds[3]},
                                {"extraction_cpu_seconds", s.cpu_seconds[0]},
                                {"matching_cpu_seconds", s.cpu_seconds[1]},
                                {"mapping_cpu_seconds", s.cpu_seconds[2]},
                                {"loop_closure_cpu_seconds", s.cpu_seconds[3]},
                                {"loop_pairs", s.loop_pairs},
                                {"refine_seconds", s.seconds[4]},
                                {"refine_cpu_seconds", s.cpu_seconds[4]},
                                {"refine_threshold_px", s.refine_threshold_px},
                                {"model", fs::relative(s.model_folder, work).string()},
                                {"seconds", clock.seconds()}});
    }

    // 3 object: cheap (no images), so redone whenever --height changes; the model is not retrained for it
    const nlohmann::json& done_object = record.stage("object");
    // (and when an older build recorded it without the fields the dense refinement needs).
    if (record.done("object") && done_object.value("height_m", nlohmann::json(nullptr)) ==
                                     (args.height_m > 0 ? nlohmann::json(args.height_m) : nlohmann::json(nullptr)) &&
        (!done_object.value("found", false) || done_object.contains("top_reach"))) {
        stage(3, "object: done in an earlier run");
    } else {
        stage(3, "object: supporting plane, up and the object's box");
        // Work folders from before the poses stage recorded its model: the usual place.
        std::string model_dir = record.stage("poses").value("model", "");
        if (model_dir.empty()) model_dir = fs::exists(work / "colmap" / "sparse_loops" / "0") ? "colmap/sparse_loops/0"
                                                                                               : "colmap/sparse/0";
        const ObjectStageResult o = object_stage(work / model_dir, args.height_m);
        if (!global.quiet) fmt::print("{}\n", o.line);
        record.finish("object", o.record);
    }

    // 4 split
    const bool hold_out = args.holdout_every > 0;
    if (record.done("split") && record.stage("split").value("every", -1) == args.holdout_every) {
        stage(4, "split: done in an earlier run");
    } else if (hold_out) {
        stage(4, fmt::format("split: holding out every {}th frame", args.holdout_every));
        const capture::SplitCounts n = capture::split_transforms(transforms, args.holdout_every);
        if (!global.quiet) fmt::print("{} training frames, {} held out\n", n.train, n.test);
        discard_trained(work, record);  // a model trained on another split has seen the held-out frames
        record.finish("split", {{"every", args.holdout_every}, {"train", n.train}, {"test", n.test}});
    } else {
        stage(4, "split: none (--holdout-every 0), training on every frame");
        for (const char* name : {"transforms_train.json", "transforms_test.json"}) {
            std::error_code ec;
            fs::remove(work / name, ec);
            if (ec) throw Error((work / name).string() + ": cannot remove (" + ec.message() + ")");
        }
        discard_trained(work, record);
        record.finish("split",
                      {{"every", 0}, {"train", record.stage("poses").value("registered", 0)}, {"test", 0}});
    }

    // 5 train
    const capture::RigSummary rig = capture::summarize_rig(transforms);
    const int downscale = args.downscale > 0 ? args.downscale : auto_downscale(rig.width, rig.height);
    const double target_seconds = args.train_steps ? 0.0 : args.train_seconds;
    nlohmann::json train_target = {{"steps", args.train_steps}, {"time", target_seconds}, {"downscale", downscale}};
    if (args.relightable) {  // absent otherwise: older records stay valid
        train_target["relight_steps"] = args.relight_steps;
        train_target["relight_points"] = args.relight_points;
        train_target["relight_pixels"] = args.relight_pixels;
    }
    std::error_code ec;
    bool trained = false;  // in this run: the object's box is refined again from the new model
    if (record.done("train") && record.stage("train").value("target", nlohmann::json()) == train_target &&
        fs::exists(model, ec)) {
        stage(5, "train: done in an earlier run (model.npt)");
    } else {
        // Training continues the whole scene where stage 7 kept it (the isolated model's grid would have to
        // grow back), and stage 7 cuts the new model again.
        if (fs::exists(scene_model, ec)) {
            fs::rename(scene_model, model, ec);
            if (ec) throw Error(scene_model.string() + ": cannot move it back to model.npt (" + ec.message() + ")");
        }
        const bool resume = fs::exists(model, ec);
        stage(5,
               fmt::format("train: {}{}", resume ? "continuing model.npt to " : "",
                           args.train_steps ? fmt::format("{} steps", args.train_steps)
                                            : fmt::format("{:.0f} s", args.train_seconds)));
        record.forget_from("train");
        TrainArgs t;
        t.data = work.string();
        t.output = model.string();
        t.split = "train";
        t.steps = args.train_steps;
        t.seconds = target_seconds;
        t.downscale = downscale;
        t.threads = args.threads;
        t.backend = backend();
        t.config = resume ? std::string() : args.config;
        t.resume = resume;
        t.resume_hint = continue_hint;
        t.subject_box = subject_box_of_record(record.stage("object"));
        t.relightable = args.relightable;
        t.relight.steps = args.relight_steps;
        t.relight.points = args.relight_points;
        t.relight.borrowing_pixels = args.relight_pixels;
        if (live) t.observer = &live->monitor();
        const int rc = run_train(t, global, interrupts);
        if (rc != 0) return rc;
        trained = true;
        const nerf::NerfModel m = nerf::load_model(model);
        const double seconds = m.training ? m.training->elapsed_seconds : 0.0;
        const uint64_t steps = m.training ? m.training->adam.step : 0;
        record.finish("train", {{"target", train_target},
                                {"steps", steps},
                                {"seconds", seconds},
                                {"downscale", downscale},
                                {"subject_rays", t.subject_box ? m.config.training.subject_rays : 0.0f},
                                {"width", rig.width / downscale},
                                {"height", rig.height / downscale}});
    }

    // The object frame goes into the model (its OBJF section), its box refined by the model's density: a scene's
    // `volume` cube then stands the object on its ground (docs/formats.md). Another --height rewrites it without
    // retraining.
    if (record.stage("object").value("found", false) && fs::exists(model, ec)) {
        nlohmann::json object = record.stage("object");
        const ObjectAttach a = attach_object(model, object, args.height_m, trained);
        if (a.record_changed) record.finish("object", object);
        if (!global.quiet && !a.line.empty()) fmt::print("{}\n", a.line);
        if (!global.quiet && a.model_written)
            fmt::print("model.npt: stores the object frame (`nerfpt info {}` shows it)\n", model.string());
    }

    // 6 eval
    if (!hold_out) {
        stage(6, "eval: skipped (no held-out frames)");
    } else if (record.done("eval")) {
        stage(6, "eval: done in an earlier run (eval/)");
    } else {
        stage(6, "eval: rendering the held-out frames");
        EvalArgs e;
        e.model = model.string();
        e.data = work.string();
        e.split = "test";
        e.output = (work / "eval").string();
        e.downscale = downscale;
        e.threads = args.threads;
        e.backend = backend();
        const Clock clock;
        const int rc = run_eval(e, global, interrupts);
        if (rc != 0) return rc;
        const nlohmann::json metrics = read_json_file(work / "eval" / "metrics.json");
        const nlohmann::json mean = metrics.value("mean", nlohmann::json::object());
        record.finish("eval", {{"views", metrics.value("images", nlohmann::json::array()).size()},
                               {"psnr", mean.value("psnr", 0.0)},
                               {"ssim", mean.value("ssim", 0.0)},
                               {"seconds", clock.seconds()}});
    }

    // 7 isolate, after eval: eval scores the whole scene against the held-out photos, which show the room.
    const bool object_alone = object_frame_of_record(record.stage("object")).has_value();
    if (!object_alone || !fs::exists(model, ec)) {
        stage(7, "isolate: skipped (no object found: model.npt holds the whole scene)");
    } else if (record.done("isolate")) {
        stage(7, args.keep_scene && !fs::exists(scene_model, ec)
                     ? "isolate: done in an earlier run without --keep-scene (the whole scene was not kept; "
                       "--force starts over)"
                     : "isolate: done in an earlier run");
    } else {
        stage(7, "isolate: the object alone in model.npt");
        record.forget_from("isolate");  // and the turntable, which shows the model
        const Clock clock;
        nerf::NerfModel m = nerf::load_model(model);
        // Cut before and not trained since (e.g. only the relight stage ran): there is no whole scene to keep.
        const bool was_isolated = m.object && m.object->object_only;
        const bool keep = args.keep_scene && !was_isolated;
        const nerf::IsolationStats st = nerf::isolate_model(m, nerf::IsolationSettings{}, model.string());
        if (keep) {
            fs::rename(model, scene_model, ec);  // a crash before the save below: stage 5 moves it back
            if (ec) throw Error(model.string() + ": cannot rename it to model_scene.npt (" + ec.message() + ")");
        }
        nerf::save_model(model, m, /*with_training=*/true);
        record.finish("isolate", {{"occupied_before", st.occupied_before},
                                  {"occupied_after", st.occupied_after},
                                  {"cut_by_region", st.cut_by_region},
                                  {"cut_off_footprint", st.cut_off_footprint},
                                  {"cut_as_floaters", st.cut_as_floaters},
                                  {"floaters", st.components - st.kept_components},
                                  {"scene_model", keep ? "model_scene.npt" : ""},
                                  {"seconds", clock.seconds()}});
        if (!global.quiet)
            fmt::print("isolate: {} of {} occupied cells kept ({} outside the box or under the plane, {} of the "
                       "table around the foot, {} in {} floaters){}\n",
                       st.occupied_after, st.occupied_before, st.cut_by_region, st.cut_off_footprint,
                       st.cut_as_floaters,
                       st.components - st.kept_components,
                       keep               ? "; the whole scene is model_scene.npt"
                       : args.keep_scene ? "; --keep-scene: model.npt was isolated in an earlier run without it, "
                                           "so the whole scene is gone (--force starts over)"
                                         : "");
    }

    // 8 turntable, at the training size by default (even: the video is yuv420p)
    const std::string res = args.turntable_res.empty() ? fmt::format("{}x{}", (rig.width / downscale) & ~1,
                                                                     (rig.height / downscale) & ~1)
                                                       : args.turntable_res;
    const nlohmann::json& done_turntable = record.stage("turntable");
    // The object alone when the object stage found it (attach_object above gave the model its frame): the room
    // and the table are not in the video, and it renders several times faster.
    if (args.turntable_frames == 0) {
        stage(8, "turntable: skipped (--turntable-frames 0)");
    } else if (record.done("turntable") && done_turntable.value("frames", 0) == args.turntable_frames &&
               done_turntable.value("res", "") == res && done_turntable.value("object", false) == object_alone) {
        stage(8, "turntable: done in an earlier run (turntable.mp4)");
    } else {
        stage(8, "turntable: rendering turntable.mp4");
        ViewArgs v;
        v.model = model.string();
        v.output = (work / "turntable.mp4").string();
        v.orbit = args.turntable_frames;
        v.res = res;
        v.fov = float(rig.fov_x_deg);
        v.elevation = float(std::clamp(rig.median_elevation_deg, -80.0, 80.0));
        v.distance = float(rig.median_distance);
        v.threads = args.threads;
        v.backend = backend();
        v.object = object_alone;
        const Clock clock;
        const int rc = run_view(v, global, interrupts);
        if (rc != 0) return rc;
        record.finish("turntable", {{"file", "turntable.mp4"},
                                    {"frames", args.turntable_frames},
                                    {"res", res},
                                    {"object", object_alone},
                                    {"elevation_deg", v.elevation},
                                    {"distance", v.distance},
                                    {"seconds", clock.seconds()}});
    }
    fmt::print("\n{}\nwrote {} and {}\n", record.markdown(), record.path().string(),
               (work / "report.md").string());
    if (live) {
        publish_stages(k_stages + 1);
        live->serve_until_interrupted();
    }
    return 0;
}

}  // namespace npt::cli
