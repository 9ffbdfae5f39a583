#include "cmd_render.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "core/error.h"
#include "core/image_io.h"
#include "core/progress.h"
#include "input_checks.h"
#include "interrupt.h"
#include "render_outputs.h"
#include "render_ranks.h"
#include "render_sequence.h"
#include "media/volume_set.h"
#include "render/backend/render_backend.h"
#include "render/renderer.h"
#include "scene/scene.h"

namespace npt::cli {
namespace fs = std::filesystem;

void parse_resolution(const std::string& text, int* width, int* height) {
    const auto bad = [&](const std::string& why) { return Error("'" + text + "' " + why); };
    const size_t x = text.find('x');
    if (x == std::string::npos || x == 0 || x + 1 == text.size())
        throw bad("is not WIDTHxHEIGHT (for example 640x480)");
    const auto side = [&](std::string_view s) {
        if (s.size() > 6 || !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }))
            throw bad("is not WIDTHxHEIGHT with positive whole numbers (for example 640x480)");
        const int v = std::stoi(std::string(s));
        if (v < 1 || v > render::k_max_resolution)
            throw bad("is out of range: each side must be 1.." + std::to_string(render::k_max_resolution));
        return v;
    };
    *width = side(std::string_view(text).substr(0, x));
    *height = side(std::string_view(text).substr(x + 1));
    if (static_cast<long long>(*width) * *height > render::k_max_pixels)
        throw bad("has more than " + std::to_string(render::k_max_pixels) + " pixels");
}

CLI::App* add_render_command(CLI::App& app, RenderArgs& args) {
    CLI::App* cmd =
        app.add_subcommand("render", "Render a scene to a linear OpenEXR image and an sRGB PNG preview");
    cmd->footer(
        "Options left out take the scene's own settings (glTF scene extras or the JSON scene's \"render\"),\n"
        "then the defaults 640x480, 64 spp, max depth 16, seed 0.\n"
        "Example: nerfpt render scenes/example/scene.gltf -o out/example.exr --spp 256 --res 1280x960\n"
        "Under mpirun -np N (a build with MPI): a sequence's frames, or a still's samples, split over the N ranks.");
    cmd->add_option("SCENE", args.scene, "Scene file: .gltf, .glb, .obj or .json (docs/formats.md)")
        ->required();
    cmd->add_option("-o,--output", args.output,
                    "Output image, must end in .exr and its folder must exist; OUT.png (sRGB preview) is "
                    "written beside it")
        ->required();
    cmd->add_option(
           "--spp", args.spp,
           "Samples per pixel, 1.." + std::to_string(render::k_max_spp) + " (default: the scene's, else 64)")
        ->check(CLI::Range(1, render::k_max_spp));
    cmd->add_option("--res", args.res,
                    "Image size in pixels, WIDTHxHEIGHT such as 640x480, each side 1.." +
                        std::to_string(render::k_max_resolution) + " (default: the scene's, else 640x480)")
        ->check(CLI::Validator(
            [](std::string& text) {
                int w = 0, h = 0;
                try {
                    parse_resolution(text, &w, &h);
                } catch (const Error& e) {
                    return std::string(e.what());
                }
                return std::string();
            },
            "WxH"));
    cmd->add_option("--max-depth", args.max_depth,
                    "Longest path in bounces, 0.." + std::to_string(render::k_max_depth) +
                        "; 0 shows emitters only (default: the scene's, else 16)")
        ->check(CLI::Range(0, render::k_max_depth));
    cmd->add_option("--seed", args.seed,
                    "Random seed, a whole number >= 0; the same seed gives the same image "
                    "(default: the scene's, else 0)")
        ->each([&args](const std::string&) { args.seed_given = true; });
    cmd->add_option("--threads", args.threads, "Worker threads, 0 = all hardware threads (default: 0)")
        ->check(CLI::Range(0, 4096));
    cmd->add_option("--backend", args.backend,
                    "Renderer: cpu (Embree + TBB) or optix (the same integrator on a GPU; built when the OptiX SDK "
                    "headers were found) (default: optix where built and a GPU is usable, else cpu)")
        ->check(CLI::Validator(
            [](std::string& name) {
                if (name == "cpu" || name == "optix" || name == "auto") return std::string();
                return "unknown backend '" + name + "' (available: cpu, optix)";
            },
            "cpu|optix"));
    cmd->add_option("--camera", args.camera,
                    "Camera to render from, by glTF node or camera name (default: the scene's first camera)");
    cmd->add_option(
           "--exposure", args.exposure,
           "PNG only: multiply by 2^STOPS before the sRGB curve and clamp, -20..20 (default: 0); the "
           "EXR is always unscaled")
        ->check(CLI::Range(-20.0f, 20.0f));
    cmd->add_flag("--transparent", args.transparent,
                  "Film > Transparent: the background is not rendered (the environment still lights the scene); "
                  "OUT.exr is RGBA with premultiplied RGB and alpha = coverage, OUT.png RGBA (default: the "
                  "scene's \"transparent\", else off)");
    CLI::Option* aov =
        cmd->add_option("--aov", args.aovs,
                        "Extra layers in OUT.exr, comma-separated, any of albedo (albedo.R/G/B), normal (world "
                        "space, normal.X/Y/Z), depth (distance along the ray, depth.Z; +inf where nothing was hit)")
            ->check(CLI::Validator(
                [](std::string& text) {
                    try {
                        render::parse_aov_list(text);
                    } catch (const Error& e) {
                        return std::string(e.what());
                    }
                    return std::string();
                },
                "LIST"));
    cmd->add_flag("--aov-files", args.aov_files,
                  "Also write each --aov layer as its own EXR beside OUT: OUT.albedo.exr and OUT.normal.exr "
                  "(R, G, B), OUT.depth.exr (Y)")
        ->needs(aov);
    cmd->add_flag("--denoise", args.denoise,
                  "OptiX backend: run OptiX's AI denoiser (albedo and normal guides); OUT.exr and OUT.png are the "
                  "denoised image, OUT.noisy.exr the render as it came out");
    cmd->add_option("--frames", args.frames,
                    "Render a sequence: frames FIRST-LAST[:STEP] (e.g. 1-240 or 1-240:2) of the scene's glTF "
                    "animation, frame F at F/FPS seconds; OUT must hold #### (shot.####.exr -> shot.0001.exr)");
    cmd->add_flag("--overwrite", args.overwrite,
                  "Sequences: render every frame again (default: frames whose EXR reads back whole are skipped)");
    cmd->add_option("--fps", args.fps, "Sequences: frames per second, 0.001..1000 (default: the scene's \"fps\", else 24)")
        ->check(CLI::Range(0.001, 1000.0));
    cmd->add_option("--animation", args.animation,
                    "The glTF animation to play, by name (default: the file's first)");
    cmd->add_option("--task-index", args.task_index,
                    "Sequences on a farm: this task's index, 0..COUNT-1; it renders the INDEX-th of COUNT contiguous "
                    "chunks of the frames (default: $SLURM_ARRAY_TASK_ID, else 0)")
        ->check(CLI::Range(0, 1 << 20));
    cmd->add_option("--task-count", args.task_count,
                    "Sequences on a farm: the number of tasks (default: $SLURM_ARRAY_TASK_COUNT, else 1)")
        ->check(CLI::Range(1, 1 << 20));
    cmd->add_option("--writers", args.writers,
                    "Sequences: frames whose files are written at once while the next ones render, 1..64; the "
                    "writers run at a lower priority than the rendering (default: half the cores, at most 8)")
        ->check(CLI::Range(1, 64));
    return cmd;
}

int run_render(const RenderArgs& args, const GlobalSettings& global, InterruptGuard& interrupts) {
    dist::MpiWorld world;  // started by mpirun: MPI, one GPU per rank of a node (render_ranks.h)
    if (world.size() > 1) return run_render_ranks(args, global, interrupts, world);
    if (!args.frames.empty()) return run_render_sequence(args, global, interrupts);
    const auto sequence_only = [](const char* option) {
        return Error(std::string(option) + ": is for sequences (with --frames FIRST-LAST)");
    };
    if (args.overwrite) throw sequence_only("--overwrite");
    if (args.fps > 0) throw sequence_only("--fps");
    if (args.task_index >= 0) throw sequence_only("--task-index");
    if (args.task_count >= 0) throw sequence_only("--task-count");
    if (args.writers > 0) throw sequence_only("--writers");
    if (args.backend == "optix") render::choose_render_backend(args.backend, nullptr);  // fails before loading
    if (args.denoise) {  // before loading: the denoiser needs the OptiX backend, chosen or by default
        if (args.backend == "cpu") throw Error("--denoise: the denoiser is OptiX's; it does not run with --backend cpu");
        std::string why;
        if (render::choose_render_backend(args.backend, &why) != "optix")
            throw Error("--denoise: the denoiser is OptiX's, and OptiX cannot be used here (" +
                        (why.empty() ? std::string("this nerfpt was built without the OptiX backend") : why) + ")");
    }
    const fs::path out_exr = args.output;
    fs::path out_png = out_exr;
    out_png.replace_extension(".png");
    fs::path out_noisy = out_exr;  // --denoise: the render as it came out
    out_noisy.replace_extension(".noisy.exr");
    check_output(out_exr);
    const uint32_t aov_mask = args.aovs.empty() ? 0u : render::parse_aov_list(args.aovs);
    const std::vector<AovFile> aov_files = args.aov_files ? aov_file_paths(out_exr, aov_mask) : std::vector<AovFile>{};

    render::RenderOptions options = render_options_from_args(args, aov_mask);

    const auto t_load = std::chrono::steady_clock::now();
    const scene::Scene scene = scene::load_scene(args.scene, scene_load_options(args));
    for (const fs::path& out : {out_exr, out_png, out_noisy})
        if (out != out_noisy || args.denoise) refuse_overwriting_inputs(out, "--output", scene_inputs(scene));
    for (const AovFile& f : aov_files) refuse_overwriting_inputs(f.path, "--aov-files", scene_inputs(scene));
    options.seed = args.seed_given ? args.seed : scene.settings.seed;
    // Chosen once the input is known to be good: the CPU fallback's note never precedes an input error.
    std::string note;
    options.backend = render::choose_render_backend(args.backend, &note);
    if (!note.empty()) spdlog::info("{}", note);
    const render::RenderOptions resolved = render::resolve_options(scene, options);
    spdlog::debug("loaded {} in {:.2f} s: {} meshes, {} triangles", args.scene,
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - t_load).count(),
                  scene.meshes.size(), scene.triangle_count());
    spdlog::info("rendering {}x{}, {} spp, max depth {}, seed {}, backend {}{}{}", resolved.width,
                 resolved.height, resolved.spp, resolved.max_depth, resolved.seed, resolved.backend,
                 resolved.transparent ? ", transparent" : "", args.aovs.empty() ? "" : ", AOVs " + args.aovs);

    ProgressSettings ps;
    ps.style = progress_style(stream_is_tty(stderr), global.quiet);
    Progress progress(ps, std::cerr);
    const auto t0 = std::chrono::steady_clock::now();
    Image denoised;
    render::AovImages aovs;
    const Image image = render::render_with_backend(
        scene, resolved, [&progress](uint64_t done, uint64_t total) { progress.update(done, total); },
        args.denoise ? &denoised : nullptr, &aovs);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    progress.finish();

    {
        auto no_interrupt = interrupts.hold();  // every file complete, or an interrupt waits for them
        if (args.denoise) write_exr_layers(out_noisy, image, {});
        const Image& shown = args.denoise ? denoised : image;
        write_exr_layers(out_exr, shown, aov_layers(aovs, aov_mask));
        write_render_png(out_png, shown, args.exposure);
        for (const AovFile& f : aov_files) write_aov_file(f, aovs);
    }
    const double samples = double(resolved.width) * resolved.height * resolved.spp;
    if (args.denoise) fmt::print("wrote {} (denoised) and {} (as rendered)\n", out_exr.string(), out_noisy.string());
    fmt::print("wrote {}\nwrote {}\n", out_exr.string(), out_png.string());
    for (const AovFile& f : aov_files) fmt::print("wrote {}\n", f.path.string());
    fmt::print("rendered {}x{} at {} spp in {} ({} samples/s)\n", resolved.width, resolved.height,
               resolved.spp, format_seconds(seconds), format_count(seconds > 0 ? samples / seconds : 0.0));
    return 0;
}

}  // namespace npt::cli
