// `nerfpt serve`: the browser viewer (src/serve/): a scene path-traced progressively and streamed to the page,
// placed and cropped there, saved back into the scene file.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "common.h"

namespace npt::cli {

struct ServeArgs {
    std::string input;  // a scene (.gltf, .glb, .obj, .json) or a model (.npt)
    std::string host = "127.0.0.1";
    int port = 7007;
    std::string backend;  // "", cpu or optix
    std::string res;      // WxH; empty: the scene's
    int spp = 0;          // target spp of the refinement; 0: the scene's
    int preview = 0;      // resolution divisor while moving; 0: 4 on the CPU, 1 on OptiX
    int threads = 0;
    std::string output_dir;  // stills; empty: beside the scene
};

CLI::App* add_serve_command(CLI::App& app, ServeArgs& args);
int run_serve(const ServeArgs& args, const GlobalSettings& global, InterruptGuard& interrupts);

}  // namespace npt::cli
