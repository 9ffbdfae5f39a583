#include "scene/scene.h"

#include <algorithm>

#include "core/error.h"
#include "scene/gltf_loader.h"
#include "scene/json_scene.h"
#include "scene/obj_loader.h"

namespace npt::scene {

size_t Scene::triangle_count() const {
    size_t n = 0;
    for (const auto& m : meshes) n += m.triangle_count();
    return n;
}

Scene load_scene(const std::filesystem::path& path, const LoadOptions& options) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    Scene scene;
    scene.source = path;
    scene.files.push_back(path);
    if (ext == ".gltf" || ext == ".glb") {
        load_gltf(path, options, scene);
    } else if (ext == ".obj") {
        load_obj(path, scene);
        if (!options.camera_name.empty())
            throw Error(path.string() + ": camera '" + options.camera_name +
                        "' not found (OBJ files have no cameras)");
    } else if (ext == ".json") {
        load_json_scene(path, options, scene);
    } else {
        throw Error(path.string() + ": unknown scene format '" + ext +
                    "' (expected .gltf, .glb, .obj or .json)");
    }
    return scene;
}

}  // namespace npt::scene
