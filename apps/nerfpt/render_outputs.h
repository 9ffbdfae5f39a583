// The files `nerfpt render` writes, shared by stills (cmd_render.cpp) and sequences (render_sequence.cpp): the
// output check, the scene's inputs that must not be written over, and the AOVs as layers or as files.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "core/image.h"
#include "core/image_io.h"
#include "input_checks.h"
#include "render/film.h"
#include "scene/scene.h"

namespace npt::cli {

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

// The AOVs as layers of OUT.exr: albedo.R, normal.X, depth.Z, ... (render/film.h).
std::vector<ExrLayer> aov_layers(const render::AovImages& aovs, uint32_t mask);

}  // namespace npt::cli
