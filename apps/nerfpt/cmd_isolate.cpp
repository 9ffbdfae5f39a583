#include "cmd_isolate.h"

#include <fmt/format.h>

#include <chrono>
#include <filesystem>

#include "core/error.h"
#include "input_checks.h"
#include "nerf/model_file.h"

namespace npt::cli {

CLI::App* add_isolate_command(CLI::App& app, IsolateArgs& args) {
    CLI::App* cmd = app.add_subcommand(
        "isolate",
        "Keep only the captured object in a model: its box, above the supporting plane, no floaters");
    cmd->footer(
        "The model must carry an object frame (`nerfpt capture` stores it). Every occupancy cell that does not\n"
        "overlap the object's box, or lies wholly below --plane-margin cells above the supporting plane, is\n"
        "emptied; in the table layer (--table-layer cells above the plane, where the table's own density\n"
        "reaches) only the cells under the object's footprint stay (its foot: the cells above the layer\n"
        "at least --footprint-opacity opaque and within --footprint-slab cells of the lowest of them,\n"
        "seen from above, widened by --footprint-margin cells); then every\n"
        "26-connected component of occupied cells but the largest with fewer than --min-component cells.\n"
        "Renders skip empty cells, so the table, the props and the floaters vanish, and the model is marked\n"
        "object-only: eval, view and bake then show only what lies in its box, cut exactly at the box and\n"
        "the plane (as --object does, and as a scene's \"placement\": \"object\" always does).\n"
        "The network is unchanged. Training the result further re-estimates the grid and clears the mark.");
    cmd->add_option("model", args.model, "Model file (.npt) with an object frame")->required();
    cmd->add_option("-o,--output", args.output, "Where to write the isolated model (may be the input)")
        ->required();
    cmd->add_option("--plane-margin", args.settings.plane_margin_cells,
                    "Cells wholly below this height above the supporting plane go, in cells of the finest cascade "
                    "(0: those straddling the plane stay; renders cut at the plane exactly)")
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--table-layer", args.settings.table_layer_cells,
                    "Height above the supporting plane, in cells of the finest cascade, below which only the "
                    "object's footprint stays (0: the plane alone cuts)")
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--footprint-margin", args.settings.footprint_margin_cells,
                    "How far the footprint reaches beyond the object's dense cells, in cells")
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber);
    cmd->add_option(
           "--footprint-slab", args.settings.footprint_slab_cells,
           "The footprint is the object's foot: its dense cells within this many cells above its lowest "
           "dense cell over the table layer, seen from above (0: every dense cell above the layer)")
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--footprint-opacity", args.settings.footprint_opacity,
                    "Opacity across a cell from which a cell above the table layer counts as the object's")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 0.999));
    cmd->add_option("--min-component", args.settings.min_component_cells,
                    "Smallest component kept apart from the largest, in cells")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    return cmd;
}

int run_isolate(const IsolateArgs& args, const GlobalSettings& global) {
    require_path(args.model, "model");
    const auto start = std::chrono::steady_clock::now();
    nerf::NerfModel m = nerf::load_model(args.model);
    const nerf::IsolationStats st = nerf::isolate_model(m, args.settings, args.model);
    nerf::save_model(args.output, m, /*with_training=*/true);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!global.quiet)
        fmt::print(
            "isolate: {} occupied cells -> {} ({} outside the box or under the plane, {} of the table around "
            "the foot, {} in {} of {} components as floaters) in {:.2f} s; wrote {}\n",
            st.occupied_before, st.occupied_after, st.cut_by_region, st.cut_off_footprint, st.cut_as_floaters,
            st.components - st.kept_components, st.components, seconds, args.output);
    return 0;
}

}  // namespace npt::cli
