// glTF 2.0 and GLB (scene/gltf_loader.h), through load_scene as `nerfpt render` reads a scene.
#include <cstring>

#include "harness_support.h"
#include "scene/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace npt;
    const bool glb = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
    const auto path = fuzz::put(glb ? "in.glb" : "in.gltf", data, size);
    fuzz::refuse_or_load([&] { scene::load_scene(path); });
    return 0;
}
