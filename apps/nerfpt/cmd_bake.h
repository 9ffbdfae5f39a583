// `nerfpt bake`: a trained model sampled onto a sparse voxel grid (.vdb, .nvdb or instant-ngp's raw .bin),
// placed in the volume cube as direct rendering places the model (nerf/nerf_placement.h).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "common.h"

namespace npt::cli {

struct BakeArgs {
    std::string model;
    std::string output;
    int res = 256;
    float voxel = 0.0f;  // model units; 0: use res
    std::string crop;    // "x0,y0,z0,x1,y1,z1"; empty: the model's box
    std::string format;  // vdb | nvdb | raw; empty: from the extension
    std::string direction = "avg";
    std::string colour = "radiance";  // radiance | albedo
    float threshold = -1.0f;  // < 0: the default
    int threads = 0;
    std::string backend;  // "", cpu or cuda (backend_option.h)
};

CLI::App* add_bake_command(CLI::App& app, BakeArgs& args);
int run_bake(const BakeArgs& args, const GlobalSettings& global, InterruptGuard& interrupts);

}  // namespace npt::cli
