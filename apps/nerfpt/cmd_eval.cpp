#include "cmd_eval.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <vector>

#include "core/error.h"
#include "core/image_io.h"
#include "core/image_metrics.h"
#include "core/progress.h"
#include "core/temp_file.h"
#include "input_checks.h"
#include "dataset_loading.h"
#include "interrupt.h"
#include "nerf/dataset.h"
#include "nerf/eval_images.h"
#include "nerf/model_file.h"
#include "backend_option.h"
#include "nerf/render_view.h"

namespace npt::cli {
namespace fs = std::filesystem;

CLI::App* add_eval_command(CLI::App& app, EvalArgs& args) {
    CLI::App* cmd = app.add_subcommand(
        "eval", "Score a trained model on a data set's held-out views: PSNR and SSIM per image and mean");
    cmd->footer(
        "Each view is rendered over a white background and compared with its ground truth composited on\n"
        "white (rgb * alpha + 1 - alpha), both as the stored sRGB-encoded values in [0, 1]: the convention\n"
        "of the NeRF papers' tables. PSNR is -10 log10(MSE) over pixels and RGB (infinite for a perfect\n"
        "match); SSIM uses an 11x11 Gaussian window (sigma 1.5), K1 0.01, K2 0.03, per channel over the\n"
        "valid region, averaged over channels. The means are plain means of the per-image values.\n"
        "With -o DIR: DIR/NAME.png (the render), DIR/NAME_compare.png ([ground truth | render | error x4\n"
        "heat map]) and DIR/metrics.json (per image and mean; infinite PSNR is written as null).\n"
        "Example: nerfpt eval lego.npt ../shared/data/nerf_synthetic/lego --every 8 -o out/lego_eval");
    cmd->add_option("MODEL", args.model, "Model file written by 'nerfpt train' (.npt)")->required();
    cmd->add_option("DATA", args.data,
                    "A transforms.json, or a folder holding transforms_{SPLIT}.json (NeRF-synthetic layout)")
        ->required();
    cmd->add_option("--split", args.split,
                    "Which transforms_{SPLIT}.json to read when DATA is a folder (default: test)");
    cmd->add_option(
        "-o,--output", args.output,
        "Folder for the renders, comparisons and metrics.json (created if missing; default: print "
        "the metrics only)");
    cmd->add_option("--every", args.every,
                    "Evaluate every N-th view only (views 0, N, 2N, ...), for a quick estimate (default: 1)")
        ->check(CLI::Range(1, 1000000));
    cmd->add_option("--downscale", args.downscale,
                    "Shrink the ground truth by this integer factor and render at that size, e.g. 2 for 800 "
                    "-> 400 px (default: 1)")
        ->check(CLI::Range(1, 64));
    cmd->add_option("--threads", args.threads, "Worker threads, 0 = all hardware threads (default: 0)")
        ->check(CLI::Range(0, 4096));
    add_backend_option(cmd, args.backend);
    return cmd;
}

namespace {

// File names from the frames' file_path ("./test/r_0" -> "r_0"), made unique by the frame index when two
// frames share a name (frames from different folders).
std::vector<std::string> output_names(const nerf::Dataset& data, const std::vector<size_t>& views) {
    std::vector<std::string> names;
    std::set<std::string> seen;
    for (size_t i : views) {
        fs::path p = fs::path(data.names[i]).filename();
        std::string ext = p.extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(),
                       [](unsigned char c) { return char(std::tolower(c)); });
        if (ext == ".png" || ext == ".jpg" || ext == ".jpeg") p = p.stem();
        std::string name = p.empty() || p == "." || p == ".." ? "frame" : p.string();
        if (!seen.insert(name).second) name += "_" + std::to_string(i);
        seen.insert(name);
        names.push_back(name);
    }
    return names;
}

}  // namespace

int run_eval(const EvalArgs& args, const GlobalSettings& global, InterruptGuard& interrupts) {
    check_requested_backend(args.backend);
    // Every path first: a typo must not cost the time of loading a model and a data set.
    require_file(args.model, "MODEL");
    require_path(args.data, "DATA");
    const fs::path out_dir = args.output;
    if (!args.output.empty()) prepare_output_folder(out_dir, "--output");
    std::optional<tbb::global_control> threads;
    if (args.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, args.threads);

    const auto t_start = std::chrono::steady_clock::now();
    const nerf::NerfModel model = nerf::load_model(args.model);
    const bool tty = stream_is_tty(stderr);
    nerf::Dataset data = load_dataset_with_progress(args.data, args.split, args.downscale, global.quiet);

    std::vector<size_t> views;
    for (size_t i = 0; i < data.cameras.size(); i += size_t(args.every)) views.push_back(i);
    const std::vector<std::string> names = output_names(data, views);
    if (!args.output.empty()) {  // -o inside the data set's folder must not replace a ground-truth image
        const auto inputs = dataset_inputs(data, {{"MODEL", args.model}});
        refuse_overwriting_inputs(out_dir / "metrics.json", "--output", inputs);
        for (const std::string& name : names)
            for (const char* suffix : {".png", "_compare.png"})
                refuse_overwriting_inputs(out_dir / (name + suffix), "--output", inputs);
    }
    // Resolved once the input is known to be good: the CPU fallback's note never precedes an input error.
    const auto renderer = nerf::make_view_renderer(resolve_backend(args.backend), model);
    spdlog::info("evaluating {} of {} views at {}x{} on {}", views.size(), data.cameras.size(), data.width,
                 data.height, renderer->device());

    nerf::ViewOptions view_options;  // white background, as the ground truth below
    const Rgb white(1.0f, 1.0f, 1.0f);
    ProgressSettings ps;
    ps.label = "eval";
    ps.unit = "rows";
    ps.style = progress_style(tty, global.quiet);
    Progress progress(ps, std::cerr);
    const uint64_t total_rows = uint64_t(views.size()) * uint64_t(data.height);
    nlohmann::json per_image = nlohmann::json::array();
    double sum_psnr = 0, sum_ssim = 0;
    for (size_t k = 0; k < views.size(); ++k) {
        const size_t i = views[k];
        const uint64_t rows_before = uint64_t(k) * uint64_t(data.height);
        const auto t0 = std::chrono::steady_clock::now();
        const Image render =
            renderer->render(data.cameras[i], view_options, [&](size_t done, size_t) {
                progress.update(rows_before + done, total_rows);
                return true;
            });
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const Image truth = nerf::ground_truth_image(data, i, white);
        const double p = psnr(render, truth), s = ssim(render, truth);
        sum_psnr += p;
        sum_ssim += s;
        per_image.push_back(
            {{"name", names[k]}, {"frame", i}, {"psnr", p}, {"ssim", s}, {"seconds", seconds}});
        if (!args.output.empty()) {
            auto no_interrupt = interrupts.hold();  // complete files, or an interrupt waits for them
            write_png(out_dir / (names[k] + ".png"), nerf::encoded_to_linear(render));
            write_png(out_dir / (names[k] + "_compare.png"),
                      nerf::encoded_to_linear(nerf::comparison_strip(truth, render)));
        }
        // The bar shares the terminal with these lines: clear it first, the next update redraws it below.
        if (ps.style == ProgressSettings::Style::Bar) std::cerr << "\r\x1b[K" << std::flush;
        fmt::print("{:<16} psnr {:6.2f} dB  ssim {:.4f}  ({})\n", names[k], p, s, format_seconds(seconds));
        std::fflush(stdout);
    }
    progress.finish();

    const double n = double(views.size());
    const double mean_psnr = sum_psnr / n, mean_ssim = sum_ssim / n;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    fmt::print("mean over {} views: psnr {:.2f} dB  ssim {:.4f}  ({} in all)\n", views.size(), mean_psnr,
               mean_ssim, format_seconds(seconds));
    if (!args.output.empty()) {
        const nlohmann::json metrics = {{"model", args.model},
                                        {"data", args.data},
                                        {"split", args.split},
                                        {"every", args.every},
                                        {"downscale", args.downscale},
                                        {"width", data.width},
                                        {"height", data.height},
                                        {"images", per_image},
                                        {"mean", {{"psnr", mean_psnr}, {"ssim", mean_ssim}}},
                                        {"seconds", seconds}};
        auto no_interrupt = interrupts.hold();
        write_text_atomic(out_dir / "metrics.json", metrics.dump(2) + "\n");
        fmt::print("wrote {} renders, comparisons and {}\n", views.size(),
                   (out_dir / "metrics.json").string());
    }
    return 0;
}

}  // namespace npt::cli
