// The files `nerfpt render` writes: output checks, the AOV layers and files, the scene's inputs that must not be
// written over. Shared by stills (cmd_render.cpp), sequences (render_sequence.cpp) and MPI stills
// (render_ranks.cpp).
#include "render_outputs.h"

#include <unistd.h>

#include <algorithm>

#include "cmd_render.h"
#include "core/error.h"
#include "media/volume_set.h"

namespace npt::cli {
namespace fs = std::filesystem;

render::RenderOptions render_options_from_args(const RenderArgs& args, uint32_t aov_mask) {
    render::RenderOptions options;
    if (!args.res.empty()) parse_resolution(args.res, &options.width, &options.height);
    options.spp = args.spp;
    options.max_depth = args.max_depth;
    options.threads = args.threads;
    options.transparent = args.transparent;
    options.aovs = aov_mask;
    return options;
}

scene::LoadOptions scene_load_options(const RenderArgs& args) {
    scene::LoadOptions load;
    load.camera_name = args.camera;
    load.animation_name = args.animation;
    return load;
}

void write_render_png(const fs::path& png, const Image& image, float exposure) {
    if (image.channels == 4)
        write_png_premultiplied(png, image, exposure);
    else
        write_png(png, image, exposure);
}

// Refuses an output we could not write, before minutes of rendering are spent.
void check_output(const fs::path& out) {
    std::string ext = out.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    if (ext != ".exr")
        throw Error("--output '" + out.string() + "': must end in .exr (a PNG preview is written beside it)");
    if (out.filename() == ".exr") throw Error("--output '" + out.string() + "': needs a file name");
    const fs::path dir = out.parent_path().empty() ? fs::path(".") : out.parent_path();
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
        throw Error("--output '" + out.string() + "': folder '" + dir.string() +
                    "' does not exist (create it first)");
    if (access(dir.c_str(), W_OK) != 0)
        throw Error("--output '" + out.string() + "': folder '" + dir.string() + "' is not writable");
    if (fs::is_directory(out, ec)) throw Error("--output '" + out.string() + "': is a folder");
}

// Every file the scene was read from: the scene files, its textures and its volumes' grids or models.
std::vector<InputFile> scene_inputs(const scene::Scene& scene) {
    std::vector<InputFile> in;
    for (const auto& f : scene.files) in.push_back({"scene file", f});
    for (const auto& t : scene.textures)
        in.push_back({"texture", t.name});  // "<embedded #i>" matches no file
    for (const auto& v : scene.volumes) {
        const fs::path declared = v.declared_in.empty() ? scene.source : v.declared_in;
        try {
            const fs::path file = media::parse_volume_desc(v.extras_json, declared.string()).file;
            in.push_back({"volume file", file.is_relative() ? declared.parent_path() / file : file});
        } catch (const Error&) {  // reported when the volume is loaded
        }
    }
    return in;
}

std::vector<AovFile> aov_file_paths(const fs::path& out_exr, uint32_t mask) {
    std::vector<AovFile> files;
    for (render::AovBits aov : {render::k_aov_albedo, render::k_aov_normal, render::k_aov_depth})
        if (mask & aov) {
            fs::path p = out_exr;
            p.replace_extension(std::string(".") + render::aov_exr_names(aov).layer + ".exr");
            files.push_back({aov, p});
        }
    return files;
}

static const Image& aov_image(const render::AovImages& aovs, render::AovBits aov) {
    return aov == render::k_aov_albedo ? aovs.albedo : aov == render::k_aov_normal ? aovs.normal : aovs.depth;
}

void write_aov_file(const AovFile& f, const render::AovImages& aovs) {
    const Image& image = aov_image(aovs, f.aov);
    write_exr_channels(f.path, image,
                       image.channels == 1 ? std::vector<std::string>{"Y"} : std::vector<std::string>{"R", "G", "B"});
}

// The AOVs as layers of OUT.exr: albedo.R, normal.X, depth.Z, ... (render/film.h).
std::vector<ExrLayer> aov_layers(const render::AovImages& aovs, uint32_t mask) {
    std::vector<ExrLayer> layers;
    for (render::AovBits aov : {render::k_aov_albedo, render::k_aov_normal, render::k_aov_depth})
        if (mask & aov) {
            const render::ExrLayerNames n = render::aov_exr_names(aov);
            ExrLayer l;
            for (const std::string& c : n.channels) l.names.push_back(std::string(n.layer) + "." + c);
            l.image = &aov_image(aovs, aov);
            layers.push_back(std::move(l));
        }
    return layers;
}

}  // namespace npt::cli
