#include "cmd_eval.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <vector>

#include "backend_option.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/image_metrics.h"
#include "core/mask_metrics.h"
#include "core/progress.h"
#include "core/temp_file.h"
#include "dataset_loading.h"
#include "input_checks.h"
#include "interrupt.h"
#include "nerf/dataset.h"
#include "nerf/eval_images.h"
#include "nerf/model_file.h"
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
        "heat map]) and DIR/metrics.json (per image and mean; infinite PSNR is written as null); with\n"
        "--alpha also DIR/NAME_alpha.png, the coverage 1 - transmittance of each pixel's ray as 8-bit grey.\n"
        "--masks DIR scores that coverage against ground-truth object masks: the view whose image is\n"
        "images/r_0.png (any folder, any extension) takes DIR/r_0.png; its alpha channel is the mask\n"
        "unless it is opaque everywhere, else its grey (mean of R, G, B); 8 or 16 bit, no sRGB curve; the\n"
        "view's size, or the original size with --downscale (box-filtered). Mask and alpha count where\n"
        "> 0.5. iou: |alpha and mask| / |alpha or mask|. bf: DAVIS's boundary F-measure (seg2bmap\n"
        "boundaries matched within ceil(0.008 x image diagonal) px). leak: mean alpha over the pixels more\n"
        "than 5 px from the mask (floaters, a table left under the object). psnr in mask: PSNR over the\n"
        "mask's pixels only, the object's own quality (with --object, whatever surrounds it is not "
        "rendered).\n"
        "An isolated object (--object, or a model from `capture`) on photos without alpha also gets psnr\n"
        "in mask over the photo: the render's white background replaced by the photo itself (rgb + (photo -\n"
        "white) x (1 - alpha)), so that the outline's pixels, where the photo mixes the object with the\n"
        "room, compare the object over the room on both sides rather than over white in the render. It\n"
        "also fills whatever the render leaves transparent inside the mask with the photo, which flatters\n"
        "a partly transparent object: alpha in mask (the mean coverage over the mask's pixels) says how\n"
        "much.\n"
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
    CLI::Option* alpha =
        cmd->add_flag("--alpha", args.alpha,
                      "Also write DIR/NAME_alpha.png, each view's coverage (1 - transmittance) as grey");
    cmd->add_option("--masks", args.masks,
                    "Folder of ground-truth object masks, DIR/<image file stem>.png per view: adds mask IoU, "
                    "boundary F and leak to the metrics (see below)");
    cmd->add_flag("--object", args.object,
                  "Render only what lies inside the model's object box (the object frame `nerfpt capture` "
                  "stores), exactly as a scene's volume with \"placement\": \"object\" cuts it: scores the "
                  "object alone against --masks");
    alpha->needs(cmd->get_option("--output"));
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

// The ground-truth mask file of each view: DIR/<stem of the view's image file>.png. Two views whose images
// share a stem (from different folders) would share a mask: refused rather than scored against the wrong one.
std::vector<fs::path> mask_files(const nerf::Dataset& data, const std::vector<size_t>& views,
                                 const fs::path& dir) {
    std::vector<fs::path> files;
    std::set<std::string> seen;
    for (size_t i : views) {
        const std::string stem = fs::path(data.image_files[i]).stem().string();
        if (!seen.insert(stem).second)
            throw Error(
                "--masks: two views have images named '" + stem + "' (frame " + std::to_string(i) +
                " and another); masks are matched by the image's file name, so they cannot be told apart");
        files.push_back(dir / (stem + ".png"));
    }
    return files;
}

// A view's mask as a binary image of the view's size; one-line errors naming the file.
Mask load_view_mask(const fs::path& file, size_t frame, const nerf::Dataset& data, int downscale) {
    std::error_code ec;
    if (!fs::exists(file, ec))
        throw Error(file.string() + ": not found (the --masks file of frame " + std::to_string(frame) + ", " +
                    data.image_files[frame].filename().string() + ")");
    Coverage c = read_coverage(file);
    if ((c.width != data.width || c.height != data.height) && downscale > 1 &&
        c.width / downscale == data.width && c.height / downscale == data.height)
        c = downscale_coverage(c, downscale);
    if (c.width != data.width || c.height != data.height)
        throw Error(file.string() + ": mask is " + std::to_string(c.width) + "x" + std::to_string(c.height) +
                    ", the view (" + data.image_files[frame].filename().string() + ") is " +
                    std::to_string(data.width) + "x" + std::to_string(data.height) +
                    (downscale > 1 ? " after --downscale " + std::to_string(downscale) : std::string()));
    return threshold_coverage(c);
}

// The coverage channel of an RGBA render.
Coverage render_alpha(const Image& render) {
    Coverage c{render.width, render.height, std::vector<float>(size_t(render.width) * size_t(render.height))};
    for (size_t i = 0; i < c.values.size(); ++i)
        c.values[i] = render.channels == 4 ? render.pixels[i * 4 + 3] : 1.0f;
    return c;
}

nlohmann::json mask_json(const MaskScores& s) {
    return {{"iou", s.iou},
            {"boundary_f", s.boundary.f},
            {"boundary_precision", s.boundary.precision},
            {"boundary_recall", s.boundary.recall},
            {"leak", s.leak}};
}

// Whether every evaluated view's photo is opaque (alpha 255 everywhere): a real capture, not a rendered
// object.
bool views_are_opaque(const nerf::Dataset& data, const std::vector<size_t>& views) {
    const size_t pixels = size_t(data.width) * size_t(data.height);
    for (size_t i : views) {
        const uint8_t* px = data.image(i);
        for (size_t p = 0; p < pixels; ++p)
            if (px[p * 4 + 3] != 255) return false;
    }
    return true;
}

}  // namespace

int run_eval(const EvalArgs& args, const GlobalSettings& global, InterruptGuard& interrupts) {
    check_requested_backend(args.backend);
    // Every path first: a typo must not cost the time of loading a model and a data set.
    require_file(args.model, "MODEL");
    require_path(args.data, "DATA");
    const bool with_masks = !args.masks.empty();
    if (with_masks) {
        require_path(args.masks, "--masks");
        if (!fs::is_directory(args.masks)) throw Error("--masks '" + args.masks + "': not a folder");
    }
    const fs::path out_dir = args.output;
    if (!args.output.empty()) prepare_output_folder(out_dir, "--output");
    std::optional<tbb::global_control> threads;
    if (args.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, args.threads);

    const auto t_start = std::chrono::steady_clock::now();
    const nerf::NerfModel model = nerf::load_model(args.model);
    if (args.object && !model.object)
        throw Error(args.model + ": --object: the model has no object frame (made by `nerfpt capture`)");
    const bool tty = stream_is_tty(stderr);
    nerf::Dataset data = load_dataset_with_progress(args.data, args.split, args.downscale, global.quiet);

    std::vector<size_t> views;
    for (size_t i = 0; i < data.cameras.size(); i += size_t(args.every)) views.push_back(i);
    const std::vector<std::string> names = output_names(data, views);
    const std::vector<fs::path> masks =
        with_masks ? mask_files(data, views, args.masks) : std::vector<fs::path>{};
    if (!args.output.empty()) {  // -o inside the data set's folder must not replace a ground-truth image
        std::vector<InputFile> extra{{"MODEL", args.model}};
        for (size_t k = 0; k < masks.size(); ++k)
            extra.push_back({"mask of frame " + std::to_string(views[k]), masks[k]});
        const auto inputs = dataset_inputs(data, extra);
        refuse_overwriting_inputs(out_dir / "metrics.json", "--output", inputs);
        for (const std::string& name : names)
            for (const char* suffix : {".png", "_compare.png", "_alpha.png"})
                refuse_overwriting_inputs(out_dir / (name + suffix), "--output", inputs);
    }
    // Every mask read and checked before the first render: a bad one fails at once, with no files written.
    std::vector<Mask> truth_masks;
    for (size_t k = 0; k < masks.size(); ++k)
        truth_masks.push_back(load_view_mask(masks[k], views[k], data, args.downscale));
    // Resolved once the input is known to be good: the CPU fallback's note never precedes an input error.
    const auto renderer = nerf::make_view_renderer(resolve_backend(args.backend), model);
    spdlog::info("evaluating {} of {} views at {}x{} on {}", views.size(), data.cameras.size(), data.width,
                 data.height, renderer->device());

    nerf::ViewOptions view_options;  // white background, as the ground truth below
    view_options.object_only = args.object;
    const Rgb white(1.0f, 1.0f, 1.0f);
    ProgressSettings ps;
    ps.label = "eval";
    ps.unit = "rows";
    ps.style = progress_style(tty, global.quiet);
    Progress progress(ps, std::cerr);
    const uint64_t total_rows = uint64_t(views.size()) * uint64_t(data.height);
    nlohmann::json per_image = nlohmann::json::array();
    double sum_psnr = 0, sum_ssim = 0, sum_psnr_inside = 0, sum_psnr_over_photo = 0, sum_alpha_inside = 0;
    size_t views_inside = 0;
    // An isolated object against photos of a whole room: inside the mask, the pixels along its outline mix
    // the object with the room in the photo and with white in the render. The object over the photo itself is
    // scored too, so that the object's own quality is not read as the background's.
    const bool object_alone = args.object || (model.object && model.object->object_only);
    const bool object_on_photos = object_alone && views_are_opaque(data, views);
    const bool over_photo = with_masks && object_on_photos;
    MaskScores mask_sum;
    for (size_t k = 0; k < views.size(); ++k) {
        const size_t i = views[k];
        const uint64_t rows_before = uint64_t(k) * uint64_t(data.height);
        const auto t0 = std::chrono::steady_clock::now();
        const Image render = renderer->render(data.cameras[i], view_options, [&](size_t done, size_t) {
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
        std::string mask_text;
        if (with_masks) {
            const Coverage alpha = render_alpha(render);
            const MaskScores m = score_mask(alpha, truth_masks[k]);
            // A view whose mask is empty (the object out of frame) has no inside: null, left out of the mean.
            const bool has_inside =
                std::find(truth_masks[k].on.begin(), truth_masks[k].on.end(), 1) != truth_masks[k].on.end();
            const double nan = std::numeric_limits<double>::quiet_NaN();
            const double p_in = has_inside ? psnr_inside(render, truth, truth_masks[k]) : nan;
            const double a_in = has_inside ? mask_coverage_inside(alpha, truth_masks[k]) : nan;
            const double p_photo =
                has_inside && over_photo
                    ? psnr_inside(nerf::over_plate(render, white, truth), truth, truth_masks[k])
                    : nan;
            if (has_inside) {
                sum_psnr_inside += p_in;
                sum_psnr_over_photo += over_photo ? p_photo : 0.0;
                sum_alpha_inside += a_in;
                ++views_inside;
            }
            mask_sum.iou += m.iou;
            mask_sum.boundary.f += m.boundary.f;
            mask_sum.boundary.precision += m.boundary.precision;
            mask_sum.boundary.recall += m.boundary.recall;
            mask_sum.leak += m.leak;
            per_image.back()["mask"] = mask_json(m);
            per_image.back()["mask"]["psnr_inside"] = has_inside ? nlohmann::json(p_in) : nlohmann::json(nullptr);
            per_image.back()["mask"]["alpha_inside"] =
                has_inside ? nlohmann::json(a_in) : nlohmann::json(nullptr);
            if (over_photo)
                per_image.back()["mask"]["psnr_inside_over_photo"] =
                    has_inside ? nlohmann::json(p_photo) : nlohmann::json(nullptr);
            mask_text = fmt::format("  iou {:.4f}  bf {:.4f}  leak {:.3f}%  psnr in mask {}", m.iou, m.boundary.f,
                                    100 * m.leak, has_inside ? fmt::format("{:.2f} dB", p_in) : "n/a (empty mask)");
            if (over_photo && has_inside)
                mask_text += fmt::format(" (over the photo {:.2f} dB, alpha in mask {:.4f})", p_photo, a_in);
        }
        if (!args.output.empty()) {
            auto no_interrupt = interrupts.hold();  // complete files, or an interrupt waits for them
            write_png(out_dir / (names[k] + ".png"), nerf::encoded_to_linear(render));
            write_png(out_dir / (names[k] + "_compare.png"),
                      nerf::encoded_to_linear(nerf::comparison_strip(truth, render)));
            if (args.alpha) write_png_grey(out_dir / (names[k] + "_alpha.png"), render, 3);
        }
        // The bar shares the terminal with these lines: clear it first, the next update redraws it below.
        if (ps.style == ProgressSettings::Style::Bar) std::cerr << "\r\x1b[K" << std::flush;
        fmt::print("{:<16} psnr {:6.2f} dB  ssim {:.4f}{}  ({})\n", names[k], p, s, mask_text,
                   format_seconds(seconds));
        std::fflush(stdout);
    }
    progress.finish();

    const double n = double(views.size());
    const double mean_psnr = sum_psnr / n, mean_ssim = sum_ssim / n;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    MaskScores mask_mean;
    std::string mask_text;
    const double psnr_inside_mean = views_inside ? sum_psnr_inside / double(views_inside)
                                                 : std::numeric_limits<double>::quiet_NaN();
    const double psnr_over_photo_mean =
        views_inside ? sum_psnr_over_photo / double(views_inside) : std::numeric_limits<double>::quiet_NaN();
    const double alpha_inside_mean =
        views_inside ? sum_alpha_inside / double(views_inside) : std::numeric_limits<double>::quiet_NaN();
    if (with_masks) {
        mask_mean.iou = mask_sum.iou / n;
        mask_mean.boundary.f = mask_sum.boundary.f / n;
        mask_mean.boundary.precision = mask_sum.boundary.precision / n;
        mask_mean.boundary.recall = mask_sum.boundary.recall / n;
        mask_mean.leak = mask_sum.leak / n;
        mask_text = fmt::format("  iou {:.4f}  bf {:.4f}  leak {:.3f}%  psnr in mask {}", mask_mean.iou,
                                mask_mean.boundary.f, 100 * mask_mean.leak,
                                views_inside ? fmt::format("{:.2f} dB", psnr_inside_mean) : "n/a (empty masks)");
        if (over_photo && views_inside)
            mask_text += fmt::format(" (over the photo {:.2f} dB, alpha in mask {:.4f})",
                                     psnr_over_photo_mean, alpha_inside_mean);
    }
    fmt::print("mean over {} views: psnr {:.2f} dB  ssim {:.4f}{}  ({} in all)\n", views.size(), mean_psnr,
               mean_ssim, mask_text, format_seconds(seconds));
    // The whole-image numbers of an isolated object compare white with the room (a few dB), which reads like
    // a broken model.
    if (object_on_photos)
        spdlog::info(
            "the model is the object alone, rendered over white, and these photos have no alpha: psnr and "
            "ssim compare white with the photos' surroundings too; the object's own numbers are the mask "
            "metrics (--masks: iou, psnr in mask)");
    if (!args.output.empty()) {
        nlohmann::json metrics = {{"model", args.model},
                                  {"data", args.data},
                                  {"split", args.split},
                                  {"every", args.every},
                                  {"downscale", args.downscale},
                                  {"width", data.width},
                                  {"height", data.height},
                                  {"images", per_image},
                                  {"mean", {{"psnr", mean_psnr}, {"ssim", mean_ssim}}},
                                  {"seconds", seconds}};
        if (with_masks) {
            metrics["masks"] = args.masks;
            metrics["boundary_tolerance_px"] = boundary_tolerance(data.width, data.height);
            metrics["leak_margin_px"] = k_leak_margin;
            metrics["mean"]["mask"] = mask_json(mask_mean);
            metrics["mean"]["mask"]["psnr_inside"] =
                views_inside ? nlohmann::json(psnr_inside_mean) : nlohmann::json(nullptr);
            metrics["mean"]["mask"]["alpha_inside"] =
                views_inside ? nlohmann::json(alpha_inside_mean) : nlohmann::json(nullptr);
            if (over_photo)
                metrics["mean"]["mask"]["psnr_inside_over_photo"] =
                    views_inside ? nlohmann::json(psnr_over_photo_mean) : nlohmann::json(nullptr);
        }
        auto no_interrupt = interrupts.hold();
        write_text_atomic(out_dir / "metrics.json", metrics.dump(2) + "\n");
        fmt::print("wrote {} renders, comparisons{} and {}\n", views.size(), args.alpha ? ", alpha maps" : "",
                   (out_dir / "metrics.json").string());
    }
    return 0;
}

}  // namespace npt::cli
