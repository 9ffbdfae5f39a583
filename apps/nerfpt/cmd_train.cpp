#include "cmd_train.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>

#include "backend_option.h"
#include "core/error.h"
#include "core/progress.h"
#include "dataset_loading.h"
#include "interrupt.h"
#include "nerf/dataset.h"
#include "nerf/model_file.h"
#include "nerf/subject_focus.h"
#include "nerf/trainer.h"
#include "relight_stage.h"
#include "status_line.h"

namespace npt::cli {
namespace fs = std::filesystem;

namespace {
constexpr uint64_t k_default_steps = 3000;
}

CLI::App* add_train_command(CLI::App& app, TrainArgs& args) {
    CLI::App* cmd =
        app.add_subcommand("train", "Train a NeRF from posed images (transforms.json) on a GPU or the CPU");
    cmd->footer(
        "The model follows instant-ngp's NeRF: a hash grid of 16 levels x 2 features on the CPU, 8 x 4 on\n"
        "a GPU (2^19 entries per level, base resolution 16, finest 2048 x aabb_scale), a 1x64 density MLP\n"
        "with 16 outputs, SH degree 4 of the view direction, a 2x64 colour MLP; occupancy grid 128^3 per\n"
        "cascade; Adam lr 1e-2; all changeable with --config (docs/formats.md lists every field).\n"
        "--steps and --time count the whole training, across resumes. Without either, 3000 steps.\n"
        "A checkpoint is written every training.checkpoint_interval steps (on a GPU: at most every 60 s\n"
        "unless --checkpoint-every is given) and on Ctrl-C (a second Ctrl-C quits at once); --resume\n"
        "continues from it (exactly on the CPU). A model trained on either backend resumes on the other.\n"
        "With --serve, a page in the browser shows the training live (its URL is printed; over SSH:\n"
        "ssh -L 7007:127.0.0.1:7007 HOST); held-out views come from transforms_test.json beside the data\n"
        "(else a few training views, marked so). When training ends the page says so and stays up until "
        "Ctrl-C.\n"
        "Example: nerfpt train ../shared/data/nerf_synthetic/lego -o lego.npt --downscale 2 --time 600");
    cmd->add_option("DATA", args.data,
                    "A transforms.json, or a folder holding transforms.json or transforms_{SPLIT}.json")
        ->required();
    cmd->add_option("-o,--output", args.output, "Model file to write (.npt); its folder must exist")
        ->required();
    cmd->add_option("--split", args.split,
                    "Which transforms_{SPLIT}.json to read when DATA is a folder without transforms.json "
                    "(default: train)");
    cmd->add_option("--steps", args.steps, "Train until this many steps in total (default: 3000)")
        ->check(CLI::Range(uint64_t(1), uint64_t(100000000)));
    cmd->add_option("--time", args.seconds, "Train until this many seconds in total, then stop and save")
        ->check(CLI::Range(0.001, 1e7));
    cmd->add_option("--config", args.config, "JSON file with model and training settings (docs/formats.md)");
    cmd->add_option("--downscale", args.downscale,
                    "Shrink the images by this integer factor before training, e.g. 2 for 400 -> 200 px "
                    "(default: 1)")
        ->check(CLI::Range(1, 64));
    cmd->add_option("--threads", args.threads, "Worker threads, 0 = all hardware threads (default: 0)")
        ->check(CLI::Range(0, 4096));
    cmd->add_option("--checkpoint-every", args.checkpoint_every,
                    "Steps between checkpoints (default: the config's, 500)")
        ->check(CLI::Range(1, 100000000));
    cmd->add_option("--surface-smoothness", args.surface_smoothness,
                    fmt::format("Weight of a loss that keeps the trained surface smooth where the images do "
                                "not say otherwise (the config's loss.surface_smoothness): better normals for "
                                "relighting. Default: {} with --relightable (unless --config gives one), else "
                                "the config's (0, off). Not with --resume: a model keeps its config",
                                k_relightable_surface_smoothness))
        ->check(CLI::Range(0.0, 1e6));
    add_backend_option(cmd, args.backend);
    cmd->add_flag(
        "--relightable", args.relightable,
        "After training, fit albedo, roughness and normals and estimate the capture light, so that "
        "renders light the object with the scene's lights (with --resume: adds them to a trained model)");
    cmd->add_option("--relight-steps", args.relight.steps,
                    fmt::format("Optimiser steps of the relight stage (default: {})", args.relight.steps))
        ->check(CLI::Range(uint64_t(1), uint64_t(10000000)));
    cmd->add_option(
           "--relight-points", args.relight.points,
           fmt::format("Surface points the relight stage fits, one per training ray that hits the object "
                       "(default: {} on a GPU, {} on the CPU)",
                       k_relight_points_gpu, k_relight_points_cpu))
        ->check(CLI::Range(64, 1 << 22));
    cmd->add_option(
           "--relight-directions", args.relight.directions,
           fmt::format("Light directions per surface point (visibility and indirect light toward each; "
                       "default: {} on a GPU, {} on the CPU)",
                       k_relight_directions_gpu, k_relight_directions_cpu))
        ->check(CLI::Range(4, 1024));
    cmd->add_option(
           "--relight-event-draws", args.relight.event_draws,
           fmt::format("Events drawn per surface point along its camera ray, as the renderer draws them; "
                       "the fit queries the fields at one of them each time (1: a single fixed point, "
                       "which the fine levels memorise; default: {})",
                       args.relight.event_draws))
        ->check(CLI::Range(1, 64));
    cmd->add_option("--relight-normals", args.relight_normals,
                    "The surface normal the stage shades with and the normal field learns: 'depth' (crossed "
                    "expected-depth stencil around the pixel, the default) or 'density' (-grad log sigma)")
        ->check(CLI::IsMember({"depth", "density"}));
    cmd->add_option("--relight-specular", args.relight_specular,
                    "How the fit shades: 'prefiltered' (the default: the environment prefiltered with each "
                    "lobe's width, the split sum of image-based lighting) or 'sampled' (the light directions of "
                    "each point, which miss narrow specular lobes and leave some of their light in the albedo; "
                    "see docs/relighting.md)")
        ->check(CLI::IsMember({"prefiltered", "sampled"}));
    cmd->add_option("--relight-diffuse", args.relight_diffuse,
                    "How the fit estimates the diffuse light: 'sampled' (the sum over each point's light "
                    "directions) or 'ratio' (the unshadowed light of the prefiltered environment times the share "
                    "of it the directions find unshadowed: no sampling noise where nothing is in the way). "
                    "Default: 'ratio' with --relight-specular prefiltered, else 'sampled'")
        ->check(CLI::IsMember({"ratio", "sampled"}));
    cmd->add_option("--relight-diffuse-lobe", args.relight_diffuse_lobe,
                    "The diffuse part of the BSDF the model is fitted for and rendered with: 'burley' (the "
                    "default: Cycles' Principled v1 diffuse, as Blender 3.x renders, brighter at grazing angles "
                    "on rough surfaces) or 'layered' (a Lambertian base below the specular layer, darker at "
                    "grazing angles; the first relightable models')")
        ->check(CLI::IsMember({"burley", "layered"}));
    cmd->add_option("--relight-roughness-prior", args.relight.roughness_prior,
                    fmt::format("Weight of the prior that keeps each point's roughness near 0.5 where the "
                                "capture light does not show it (default: {})",
                                args.relight.roughness_prior))
        ->check(CLI::Range(0.0f, 100.0f));
    cmd->add_option("--relight-huber", args.relight.huber_delta,
                    "Huber threshold of the fit's photometric loss, in sRGB units: residuals beyond it count "
                    "linearly, so a point's albedo follows the median of its views more than their mean (a "
                    "highlight the fit cannot explain moves it less). 0: squared error (default: 0)")
        ->check(CLI::Range(0.0f, 1.0f));
    cmd->add_option(
           "--relight-footprint", args.relight.footprint_queries,
           fmt::format("Where the fit reads the fields for a training pixel: 1, at one point on its camera ray "
                       "(which fits the albedo blurred by the pixel); 4 or 9, averaged over a 2x2 or 3x3 grid "
                       "across the pixel's square on the surface, as the photo's pixel averages the object: a "
                       "sharper albedo, at that many times the fit's network work (default: {})",
                       k_relight_footprint))
        ->check(CLI::IsMember({1, 4, 9}));
    cmd->add_option("--relight-ground", args.relight.ground_share,
                    fmt::format("The capture light below the horizon starts at this share of the sky above it "
                                "(the ground reflects part of the sky's light); the images move it where they "
                                "can (default: {})",
                                args.relight.ground_share))
        ->check(CLI::Range(0.001f, 1.0f));
    cmd->add_option("--relight-average", args.relight.average_decay,
                    fmt::format("The fitted fields are the moving average of the fit's parameters, weighted by "
                                "this factor per step: 0.99 averages the last ~100 steps, 0 keeps the last "
                                "step's (default: {})",
                                args.relight.average_decay))
        ->check(CLI::Range(0.0f, 0.9999f));
    cmd->add_option("--relight-seed", args.relight.seed,
                    "Seed of the relight stage's random draws (points, light directions, batches); two runs "
                    "with different seeds show the stage's run-to-run spread (default: the model's training "
                    "seed)")
        ->each([&args](const std::string&) { args.relight.seed_given = true; });
    cmd->add_option("--relight-batch", args.relight.batch,
                    fmt::format("Surface points per optimiser step (default: {} on a GPU, {} on the CPU)",
                                k_relight_batch_gpu, k_relight_batch_cpu))
        ->check(CLI::Range(16, 1 << 20));
    cmd->add_option(
           "--relight-normal-smoothing", args.relight.normal_smoothing,
           fmt::format("Radius (model units, the unit cube) over which the surface normals are averaged, "
                       "edges kept: removes the small bumps a NeRF carves into its density (default: {}; "
                       "0 turns it off)",
                       args.relight.normal_smoothing))
        ->check(CLI::Range(0.0f, 0.5f));
    cmd->add_option(
           "--relight-pixels", args.relight.borrowing_pixels,
           fmt::format("Training pixels (drawn at random, with replacement) that supervise the "
                       "albedo without light directions of their own: "
                       "each borrows the normal and light of the nearest surface point (one camera ray "
                       "each instead of --relight-directions light rays; default: {} on a GPU, {} on the "
                       "CPU)",
                       k_relight_pixels_gpu, k_relight_pixels_cpu))
        ->check(CLI::Range(0, 1 << 24));
    cmd->add_option(
           "--relight-pool", args.relight.pooled_neighbours,
           fmt::format("Nearby surface points whose light directions each point also shades with (their "
                       "shadowing and indirect light, no rays of its own): a less noisy shading estimate, "
                       "so a cleaner albedo, at more fitting time per step (default: {})",
                       k_relight_pool))
        ->check(CLI::Range(0, 64));
    cmd->add_option(
           "--relight-table", args.relight.table_log2,
           fmt::format("log2 of the hash entries per level of the albedo/roughness/normal grid: more "
                       "resolves finer texture, at 12 x 2 x 4 bytes x 2^N of model size (default: {})",
                       args.relight.table_log2))
        ->check(CLI::Range(12, 24));
    cmd->add_option(
           "--relight-resolution", args.relight.finest_resolution,
           fmt::format("Finest resolution of that grid across the model's box (times aabb_scale): the "
                       "smallest texture detail the albedo can hold (default: {})",
                       args.relight.finest_resolution))
        ->check(CLI::Range(32.0f, 8192.0f));
    cmd->add_flag("--resume", args.resume, "Continue training the model in --output where it stopped");
    cmd->add_flag("--force", args.force, "Overwrite --output if it exists (without --resume)")
        ->excludes(cmd->get_option("--resume"));
    add_live_serve_options(cmd, args.serve);
    return cmd;
}

namespace {

void check_output(const fs::path& out, bool resume, bool force) {
    const fs::path dir = out.parent_path().empty() ? fs::path(".") : out.parent_path();
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
        throw Error("--output '" + out.string() + "': folder '" + dir.string() + "' does not exist");
    if (access(dir.c_str(), W_OK) != 0)
        throw Error("--output '" + out.string() + "': folder '" + dir.string() + "' is not writable");
    if (fs::is_directory(out, ec)) throw Error("--output '" + out.string() + "': is a folder");
    if (resume && !fs::exists(out, ec))
        throw Error("--resume: '" + out.string() + "' does not exist (train without --resume first)");
    if (!resume && !force && fs::exists(out, ec))
        throw Error("--output '" + out.string() +
                    "' exists: pass --resume to continue training it or --force to start over");
}

// The training's status line: a bar over steps (or time), the loss and the rate. The text is composed only
// when the line is due.
void show_train_progress(StatusLine& line, const nerf::StepStats& s, double fraction, double rays_per_s,
                         double elapsed, bool force) {
    if (!line.due(force)) return;
    line.print(
        fmt::format("train {} {:3.0f}% step {} loss {:.5f} psnr {:.2f} dB {} rays/s {} samples/step {}",
                    format_bar(fraction, 20), 100.0 * fraction, s.step, s.loss, nerf::psnr_from_mse(s.mse),
                    format_count(rays_per_s), format_count(double(s.samples)), format_eta_clock(elapsed)));
}

}  // namespace

int run_train(const TrainArgs& args, const GlobalSettings& global, InterruptGuard& interrupts) {
    check_requested_backend(args.backend);
    const fs::path out = args.output;
    check_output(out, args.resume, args.force);
    refuse_overwriting_inputs(out, "--output", {{"DATA", args.data}, {"--config", args.config}});
    std::optional<tbb::global_control> threads;
    if (args.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, args.threads);
    // The page binds first: a port in use fails before the data loads.
    std::unique_ptr<LiveTraining> live;
    nerf::TrainingObserver* observer = args.observer;
    if (args.serve.enabled && !observer) {
        live = std::make_unique<LiveTraining>(args.serve, "nerfpt train " + args.data);
        observer = &live->monitor();
    }

    nerf::NerfModel model;
    if (args.resume) {
        if (!args.config.empty())
            throw Error("--config: a resumed model keeps the config it was trained with (stored in '" +
                        out.string() + "')");
        if (args.surface_smoothness >= 0.0f)
            throw Error("--surface-smoothness: a resumed model keeps the config it was trained with (stored in '" +
                        out.string() + "')");
        model = nerf::load_model(out);
        if (!model.training)
            throw Error("--resume: '" + out.string() + "' was saved without its training state");
    }
    const bool tty = stream_is_tty(stderr);
    nerf::Dataset data = load_dataset_with_progress(args.data, args.split, args.downscale, global.quiet);
    refuse_overwriting_inputs(out, "--output", dataset_inputs(data));
    // A few pixels around the box's projection: the lens's distortion is not in it.
    if (args.subject_box) data.subject_rects = nerf::subject_rects(data.cameras, *args.subject_box, 4.0f);
    // Resolved once the input is known to be good: the CPU fallback's note never precedes an input error.
    const nerf::Backend backend = resolve_backend(args.backend);
    if (!args.resume) {
        const nerf::NerfConfig base =
            backend == nerf::Backend::cuda ? nerf::cuda_default_config() : nerf::cpu_default_config();
        nerf::NerfConfig config = args.config.empty() ? base : nerf::load_config(args.config, base);
        if (args.surface_smoothness >= 0.0f)
            config.loss.surface_smoothness = args.surface_smoothness;
        else if (args.relightable && args.config.empty())
            config.loss.surface_smoothness = k_relightable_surface_smoothness;
        model =
            nerf::create_model(config, data.aabb_scale, nerf::ngp_world_to_model(data.scale, data.offset));
    }
    // Where the cameras looked: a bake averages the colour over these directions (bake/bake_grid.h). Also set
    // when resuming a model written before they were stored.
    model.view_directions = nerf::training_view_directions(data.cameras, model.world_to_model);
    if (args.checkpoint_every > 0) model.config.training.checkpoint_interval = args.checkpoint_every;
    const uint64_t target_steps = args.steps ? args.steps : (args.seconds > 0 ? UINT64_MAX : k_default_steps);
    spdlog::info("training on {} frames of {}x{}, aabb_scale {}, {} parameters{}", data.cameras.size(),
                 data.width, data.height, data.aabb_scale, model.params.size(),
                 args.resume ? fmt::format(", resuming at step {}", model.training->adam.step) : "");
    if (!data.subject_rects.empty()) {
        double share = 0;
        for (const nerf::PixelRect& r : data.subject_rects)
            share += double(r.x1 - r.x0) * (r.y1 - r.y0) / (double(data.width) * data.height);
        spdlog::info(
            "{:.0f}% of the rays drawn where the images see the object (its box: {:.0f}% of an image on "
            "average)",
            100.0 * model.config.training.subject_rays, 100.0 * share / double(data.subject_rects.size()));
    }

    std::unique_ptr<nerf::TrainerBackend> trainer_ptr = nerf::make_trainer(backend, model, data);
    nerf::TrainerBackend& trainer = *trainer_ptr;
    spdlog::info("training on {}", trainer.device());
    // Training re-estimates the occupancy grid: an isolated model's cut (nerfpt isolate) no longer holds, and
    // its renders show the whole model again.
    if (model.object && trainer.steps_done() < target_steps &&
        (args.seconds <= 0 || model.training->elapsed_seconds < args.seconds))
        model.object->object_only = false;
    // A GPU step takes milliseconds: writing a checkpoint (hundreds of MB) every interval of steps would cost
    // more than the training, so without an explicit --checkpoint-every a GPU saves at most once a minute.
    const double min_checkpoint_seconds =
        backend == nerf::Backend::cuda && args.checkpoint_every == 0 ? 60.0 : 0.0;
    double last_checkpoint = Progress::steady_seconds();
    auto save = [&] {
        last_checkpoint = Progress::steady_seconds();
        trainer.sync_model();
        auto no_interrupt = interrupts.hold();  // the file is complete, or an interrupt waits for it
        nerf::save_model(out, model, true);
    };
    if (observer) {
        nerf::TrainingStart ts;
        ts.data = &data;
        ts.data_path = args.data;
        ts.split = args.split;
        ts.downscale = args.downscale;
        ts.world_to_model = model.world_to_model;
        ts.backend = backend;
        ts.device = trainer.device();
        ts.start_step = trainer.steps_done();
        ts.target_steps = target_steps;
        ts.target_seconds = args.seconds;
        observer->on_start(ts);
    }
    interrupts.set_cooperative(true);
    StatusLine progress(tty, global.quiet);
    const uint64_t interval = uint64_t(model.config.training.checkpoint_interval);
    double rays_ema = 0;
    nerf::StepStats stats;
    nerf::StepStats::Phases phase_total;
    bool interrupted = false;
    while (trainer.steps_done() < target_steps &&
           (args.seconds <= 0 || model.training->elapsed_seconds < args.seconds)) {
        stats = trainer.step();
        const auto& p = stats.phases;
        phase_total.march += p.march;
        phase_total.forward += p.forward;
        phase_total.loss += p.loss;
        phase_total.backward += p.backward;
        phase_total.grid_backward += p.grid_backward;
        phase_total.adam += p.adam;
        phase_total.occupancy += p.occupancy;
        const double rate = stats.seconds > 0 ? stats.rays / stats.seconds : 0.0;
        rays_ema = rays_ema == 0 ? rate : 0.9 * rays_ema + 0.1 * rate;
        const double elapsed = model.training->elapsed_seconds;
        const double fraction = args.seconds > 0 && !args.steps
                                    ? std::min(1.0, elapsed / args.seconds)
                                    : std::min(1.0, double(trainer.steps_done()) / double(target_steps));
        show_train_progress(progress, stats, fraction, rays_ema, elapsed, false);
        if (observer) {
            observer->on_step(stats, elapsed, fraction);
            if (observer->snapshot_due()) {
                trainer.sync_model();
                observer->on_snapshot(model, trainer.steps_done());
            }
        }
        if (!std::isfinite(stats.loss))
            throw Error("training diverged at step " + std::to_string(stats.step) +
                        " (loss is not finite); the last checkpoint in '" + out.string() + "' is kept");
        if (interrupts.stop_requested()) {
            interrupted = true;
            break;
        }
        if (trainer.steps_done() % interval == 0 &&
            Progress::steady_seconds() - last_checkpoint >= min_checkpoint_seconds)
            save();
    }
    show_train_progress(progress, stats, 1.0, rays_ema, model.training->elapsed_seconds, true);
    progress.finish();
    if (args.relightable && !interrupted) {
        save();  // the NeRF is safe on disk before the relight stage starts
        trainer.sync_model();
        RelightStageOptions ro = args.relight;
        ro.normals = args.relight_normals == "density" ? nerf::NormalEstimator::density
                                                       : nerf::NormalEstimator::depth_stencil;
        ro.specular = args.relight_specular == "prefiltered" ? nerf::SpecularEstimate::prefiltered
                                                             : nerf::SpecularEstimate::sampled;
        const std::string diffuse = args.relight_diffuse.empty()
                                        ? (args.relight_specular == "prefiltered" ? "ratio" : "sampled")
                                        : args.relight_diffuse;
        ro.diffuse = diffuse == "ratio" ? nerf::DiffuseEstimate::ratio : nerf::DiffuseEstimate::sampled;
        ro.diffuse_lobe =
            args.relight_diffuse_lobe == "layered" ? nerf::IntrinsicDiffuse::layered : nerf::IntrinsicDiffuse::burley;
        ro.quiet = global.quiet;
        ro.backend = backend;
        interrupted = !run_relight_stage(model, data, ro, interrupts);
    }
    const auto& pt = phase_total;
    if (backend == nerf::Backend::cpu)
        spdlog::debug(
            "time per phase: march {:.1f} s, field forward {:.1f} s, loss {:.1f} s, MLP backward {:.1f} s, "
            "hash-grid backward {:.1f} s, Adam {:.1f} s, occupancy grid {:.1f} s",
            pt.march, pt.forward, pt.loss, pt.backward, pt.grid_backward, pt.adam, pt.occupancy);
    save();
    interrupts.set_cooperative(false);
    fmt::print("wrote {} after {} steps ({} of training), last batch psnr {:.2f} dB{}\n", out.string(),
               trainer.steps_done(), format_seconds(model.training->elapsed_seconds),
               nerf::psnr_from_mse(stats.mse),
               model.config.loss.surface_smoothness > 0.0f
                   ? fmt::format(", surface-smoothness loss {:.5f}", stats.smoothness)
                   : std::string());
    if (observer) {
        observer->on_snapshot(model, trainer.steps_done());  // the model as saved: its held-out PSNR
        observer->on_finish(trainer.steps_done(), model.training->elapsed_seconds, interrupted);
    }
    if (live && !interrupted) live->serve_until_interrupted();
    if (interrupted) {
        const std::string hint = !args.resume_hint.empty()
                                     ? args.resume_hint
                                     : fmt::format("nerfpt train {} -o {} --resume{}", args.data, args.output,
                                                   args.relightable ? " --relightable" : "");
        fmt::print(stderr, "nerfpt: interrupted; continue with: {}\n", hint);
        return 128 + interrupts.stop_signal();
    }
    return 0;
}

}  // namespace npt::cli
