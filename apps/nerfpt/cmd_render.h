// `nerfpt render`: load a scene, render it on the chosen backend, write linear EXR plus a tonemapped PNG.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

#include "common.h"

namespace npt::cli {

struct RenderArgs {
    std::string scene;
    std::string output;
    int spp = 0;         // 0: the scene's setting
    std::string res;     // "WxH"; empty: the scene's setting
    int max_depth = -1;  // -1: the scene's setting
    uint64_t seed = 0;
    bool seed_given = false;
    int threads = 0;
    std::string backend;  // "", cpu or optix (render/backend/render_backend.h)
    std::string camera;
    float exposure = 0.0f;
    bool denoise = false;  // OptiX's denoiser: OUT.exr denoised, OUT.noisy.exr as rendered
    bool transparent = false;  // Film > Transparent: RGBA without the background (or the scene's setting)
    std::string aovs;          // "albedo,normal,depth" or a subset: layers of OUT.exr (render/film.h)
    bool aov_files = false;    // each AOV also as its own EXR beside OUT: OUT.albedo.exr, ...
    // Sequences (render_sequence.h): --frames FIRST-LAST[:STEP] writes OUT with #### replaced by each frame.
    std::string frames;
    bool overwrite = false;    // render frames whose EXR is already whole again
    double fps = 0.0;          // 0: the scene's (extras "fps"), else 24
    std::string animation;     // glTF animation by name; empty: the file's first
    int task_index = -1;       // -1: SLURM_ARRAY_TASK_ID, else 0
    int task_count = -1;       // -1: SLURM_ARRAY_TASK_COUNT, else 1
    int writers = 0;           // frames written at once while the next render; 0: FrameWriter's default
};

// Parses "640x480" strictly: digits only, each side in 1..render::k_max_resolution. Throws npt::Error.
void parse_resolution(const std::string& text, int* width, int* height);

CLI::App* add_render_command(CLI::App& app, RenderArgs& args);
int run_render(const RenderArgs& args, const GlobalSettings& global, InterruptGuard& interrupts);

}  // namespace npt::cli
