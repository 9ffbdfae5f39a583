#include "cmd_bake.h"

#include "backend_option.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/global_control.h>

#include <charconv>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>

#include "bake/bake_grid.h"
#include "bake/grid_writers.h"
#include "core/error.h"
#include "core/progress.h"
#include "input_checks.h"
#include "interrupt.h"
#include "nerf/model_file.h"

namespace npt::cli {
namespace fs = std::filesystem;

namespace {

// Comma-separated finite floats, exactly `count` of them; throws npt::Error naming the option.
std::vector<float> parse_floats(const std::string& text, size_t count, const std::string& option,
                                const std::string& form) {
    std::vector<float> v;
    size_t start = 0;
    while (start <= text.size()) {
        size_t stop = text.find(',', start);
        if (stop == std::string::npos) stop = text.size();
        const std::string tok = text.substr(start, stop - start);
        float x = 0;
        const auto [end, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), x);
        if (tok.empty() || ec != std::errc() || end != tok.data() + tok.size() || !std::isfinite(x))
            throw Error(option + " '" + text + "': expected " + form + " (finite numbers)");
        v.push_back(x);
        start = stop + 1;
    }
    if (v.size() != count) throw Error(option + " '" + text + "': expected " + form);
    return v;
}

}  // namespace

CLI::App* add_bake_command(CLI::App& app, BakeArgs& args) {
    CLI::App* cmd = app.add_subcommand(
        "bake", "Bake a trained model to a sparse voxel grid: OpenVDB, NanoVDB or instant-ngp raw");
    cmd->footer(
        "The crop box fills the volume cube's local box [-1,1]^3 as in direct rendering: local x, y, z = "
        "model\n"
        "z, x, y (training-world x, y, z). .vdb/.nvdb: grids 'density' (sigma per local unit) and 'color'\n"
        "(linear RGB); raw: float32 R,G,B (sRGB),sigma (per model unit). Only voxels in occupied cells with\n"
        "sigma >= --threshold are stored (raw: written as 0). Colour is baked for one direction or "
        "averaged\n"
        "(--colour radiance), or is a relightable model's albedo (--colour albedo, metadata nerfpt_colour):\n"
        "view-dependent effects (highlights, reflections) are lost in a bake. See docs/formats.md.\n"
        "Example: nerfpt bake out/lego.npt -o out/lego.vdb --res 256");
    cmd->add_option("MODEL", args.model, "Trained model file (.npt)")->required();
    cmd->add_option("-o,--output", args.output,
                    "Output grid: .vdb, .nvdb or .bin (raw; 'WxHxD_' is put in front of the name unless it "
                    "has the size); its folder must exist")
        ->required();
    auto* res = cmd->add_option("--res", args.res,
                                "Voxels along the crop's longest side, 1.." +
                                    std::to_string(bake::k_max_bake_resolution) +
                                    "; the other sides proportional (default: 256)")
                    ->check(CLI::Range(1, bake::k_max_bake_resolution));
    cmd->add_option("--voxel", args.voxel, "Voxel size in model units, instead of --res")
        ->excludes(res)
        ->check(CLI::PositiveNumber);
    cmd->add_option("--crop", args.crop,
                    "x0,y0,z0,x1,y1,z1: the model-space box to bake, inside the model's box (default: all of "
                    "it, 0.5 -+ aabb_scale/2)");
    cmd->add_option("--format", args.format, "vdb, nvdb or raw (default: from the output's extension)");
    cmd->add_option("--direction", args.direction,
                    "avg: colour averaged over 16 directions; or x,y,z: the colour seen looking along this "
                    "direction (training-world axes). View-dependent effects are lost either way "
                    "(default: avg)");
    cmd->add_option("--colour", args.colour,
                    "radiance: the trained colour (the capture's light), for emission; albedo: a relightable "
                    "model's diffuse albedo (linear), for a renderer that scatters light with the grid "
                    "(default: radiance)")
        ->check(CLI::IsMember({"radiance", "albedo"}));
    cmd->add_option("--threshold", args.threshold,
                    "Drop voxels with sigma below this (per model unit); default: occupancy.threshold / "
                    "(8 * min_step), 0.74 with the default config")
        ->check(CLI::NonNegativeNumber);
    add_backend_option(cmd, args.backend);
    cmd->add_option("--threads", args.threads, "Worker threads, 0 = all hardware threads (default: 0)")
        ->check(CLI::Range(0, 4096));
    return cmd;
}

int run_bake(const BakeArgs& args, const GlobalSettings& global, InterruptGuard& interrupts) {
    check_requested_backend(args.backend);
    // Everything that can be checked without the model first, so a typo fails at once.
    require_file(args.model, "MODEL");
    fs::path out = args.output;
    const bake::GridFormat format =
        args.format.empty() ? bake::grid_format_from_path(out) : bake::grid_format_from_name(args.format);
    bake::check_extension(out, format);
    require_writable_parent(out, "--output");
    bake::BakeSettings settings;
    settings.resolution = args.res;
    settings.voxel_size = args.voxel;
    if (!args.crop.empty()) {
        const auto v = parse_floats(args.crop, 6, "--crop", "x0,y0,z0,x1,y1,z1");
        settings.crop = nerf::CropBox{Vec3(v[0], v[1], v[2]), Vec3(v[3], v[4], v[5])};
    }
    if (args.direction != "avg") {
        const auto v = parse_floats(args.direction, 3, "--direction", "avg or x,y,z");
        settings.direction = Vec3(v[0], v[1], v[2]);
    }
    if (args.threshold >= 0.0f) settings.threshold = args.threshold;
    settings.colour = args.colour == "albedo" ? bake::BakeColour::albedo : bake::BakeColour::radiance;
    std::optional<tbb::global_control> threads;
    if (args.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, args.threads);

    const nerf::NerfModel model = nerf::load_model(args.model);
    bake::check_colour_settings(model, settings, args.model);
    const bake::BakeLayout layout = bake::make_bake_layout(model, settings);
    if (format == bake::GridFormat::raw) {
        bake::check_raw_size(layout);
        out = bake::raw_output_path(out, layout);
    }
    refuse_overwriting_inputs(out, "--output", {{"MODEL", args.model}});
    spdlog::info(
        "baking {} to {}x{}x{} voxels (local x, y, z), crop ({:g}, {:g}, {:g}) .. ({:g}, {:g}, {:g})",
        args.model, layout.dims[0], layout.dims[1], layout.dims[2], layout.crop.min.x, layout.crop.min.y,
        layout.crop.min.z, layout.crop.max.x, layout.crop.max.y, layout.crop.max.z);

    ProgressSettings ps;
    ps.label = "bake";
    ps.unit = "voxels";
    ps.style = progress_style(stream_is_tty(stderr), global.quiet);
    Progress progress(ps, std::cerr);
    const auto t0 = std::chrono::steady_clock::now();
    // Resolved once the input is known to be good: the CPU fallback's note never precedes an input error.
    const std::unique_ptr<bake::BakeField> field = nerf::make_bake_field(resolve_backend(args.backend), model);
    const bake::BakedGrid grid = bake::bake_model(
        model, settings, [&](uint64_t done, uint64_t total) { progress.update(done, total); }, field.get());
    progress.finish();
    const double bake_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (grid.density_voxels == 0)
        spdlog::warn("no voxel has sigma >= {:g}: the grid is empty (a lower --threshold, another --crop?)",
                     grid.threshold);

    const auto t1 = std::chrono::steady_clock::now();
    {
        auto no_interrupt = interrupts.hold();  // a complete file, or an interrupt waits for it
        switch (format) {
            case bake::GridFormat::vdb:
                bake::write_vdb(out, grid);
                break;
            case bake::GridFormat::nvdb:
                bake::write_nvdb(out, grid);
                break;
            case bake::GridFormat::raw:
                bake::write_raw(out, grid);
                break;
        }
    }
    const double write_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    std::error_code ec;
    const auto bytes = fs::file_size(out, ec);
    fmt::print("wrote {} ({} bytes)\n", out.string(), ec ? 0 : bytes);
    fmt::print(
        "baked {}x{}x{} voxels: {} with density, {} colour-only (sigma threshold {:g} per model unit) "
        "in {}, written in {}\n",
        layout.dims[0], layout.dims[1], layout.dims[2], grid.density_voxels,
        grid.size() - grid.density_voxels, grid.threshold, format_seconds(bake_s), format_seconds(write_s));
    return 0;
}

}  // namespace npt::cli
