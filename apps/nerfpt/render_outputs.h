// The files `nerfpt render` writes, shared by stills (cmd_render.cpp), sequences (render_sequence.cpp) and
// stills split over MPI ranks (render_ranks.cpp): the output check, the scene's inputs that must not be written
// over, the PNG beside the EXR and the AOVs as layers or as files; also the options the command line sets.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "core/image.h"
#include "core/image_io.h"
#include "input_checks.h"
#include "render/film.h"
#include "render/renderer.h"
#include "scene/scene.h"

namespace npt::cli {

struct RenderArgs;

// What the command line sets of the render options: resolution, spp, depth, threads, transparency, the AOVs of
// `aov_mask`. The seed and the backend are left to the caller, which chooses them once the scene is loaded.
render::RenderOptions render_options_from_args(const RenderArgs& args, uint32_t aov_mask);
// The scene's load options: --camera and --animation.
scene::LoadOptions scene_load_options(const RenderArgs& args);

// Refuses an output we could not write (not .exr, no folder, not writable), before minutes of rendering.
void check_output(const std::filesystem::path& out);

// Every file the scene was read from: the scene files, its textures and its volumes' grids or models.
std::vector<InputFile> scene_inputs(const scene::Scene& scene);

// --aov-files: one plain EXR per AOV beside OUT (OUT.albedo.exr, ...), channels that any EXR reader takes as an
// image (OpenCV reads only R, G, B, A or Y).
struct AovFile {
    render::AovBits aov;
    std::filesystem::path path;
};
std::vector<AovFile> aov_file_paths(const std::filesystem::path& out_exr, uint32_t mask);
void write_aov_file(const AovFile& f, const render::AovImages& aovs);

// The tonemapped PNG beside OUT.exr: premultiplied when the image is RGBA (a transparent film).
void write_render_png(const std::filesystem::path& png, const Image& image, float exposure);

// The AOVs as layers of OUT.exr: albedo.R, normal.X, depth.Z, ... (render/film.h).
std::vector<ExrLayer> aov_layers(const render::AovImages& aovs, uint32_t mask);

}  // namespace npt::cli
