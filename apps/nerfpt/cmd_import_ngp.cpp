#include "cmd_import_ngp.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "input_checks.h"
#include "nerf/model_file.h"
#include "nerf/ngp_snapshot.h"

namespace npt::cli {

CLI::App* add_import_ngp_command(CLI::App& app, ImportNgpArgs& args) {
    CLI::App* cmd =
        app.add_subcommand("import-ngp", "Convert an instant-ngp NeRF snapshot into a nerfpt model file");
    cmd->footer(
        "Reads a snapshot saved by instant-ngp (.msgpack, or .ingp compressed with gzip/zlib): its\n"
        "network config, parameters and density grid. Supported: HashGrid position encoding, SH degree 4\n"
        "directions, FullyFused/Cutlass MLPs with ReLU up to 128 neurons, aabb_scale 1, LDR data; anything\n"
        "else is refused with the field named. Exp density and sigmoid colour activations are assumed\n"
        "(snapshots do not record them). Levels that tiny-cuda-nn keeps dense but nerfpt hashes are fitted\n"
        "and reported. Layout and limits: docs/formats.md, 'instant-ngp snapshots'.\n"
        "Example: nerfpt import-ngp lego.ingp -o lego.npt");
    cmd->add_option("SNAPSHOT", args.snapshot, "instant-ngp snapshot (.msgpack or .ingp)")->required();
    cmd->add_option("-o,--output", args.output, "Model file to write (.npt)")->required();
    return cmd;
}

int run_import_ngp(const ImportNgpArgs& args, const GlobalSettings& /*global*/) {
    refuse_overwriting_inputs(args.output, "--output", {{"SNAPSHOT", args.snapshot}});
    nerf::NgpImport imp = nerf::import_ngp_snapshot(args.snapshot);
    for (const std::string& note : imp.notes) spdlog::warn("{}", note);
    const nerf::NerfLayout layout = imp.model.layout();
    size_t dense = 0;
    for (const auto& l : imp.levels) dense += l.dense_here ? 1 : 0;
    spdlog::info(
        "{} levels ({} dense) x {} features, 2^{} entries, density MLP {}x{}, colour MLP {}x{}, "
        "{} parameters, trained {} steps",
        layout.grid.levels, dense, layout.grid.features_per_level, layout.grid.log2_table_size,
        layout.density.hidden_layers, layout.density.width, layout.color.hidden_layers, layout.color.width,
        layout.total, imp.training_step);
    nerf::save_model(args.output, imp.model, /*with_training=*/false);
    fmt::print("wrote {} ({:.1f}% of the occupancy grid occupied)\n", args.output,
               100.0 * imp.model.occupancy.occupied_fraction());
    return 0;
}

}  // namespace npt::cli
