// Our JSON scene format (scene/json_scene.h). The scratch folder holds tri.obj and cam.gltf for it to
// include.
#include "harness_support.h"
#include "scene/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace npt;
    static const bool assets = [] {
        fuzz::put("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n");
        fuzz::put(
            "cam.gltf",
            R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"name": "cam",
                  "camera": 0, "translation": [0, 0, 7]}], "cameras": [{"type": "perspective",
                  "perspective": {"yfov": 0.5, "znear": 0.1}}]})");
        return true;
    }();
    (void)assets;
    const auto path = fuzz::put("in.json", data, size);
    fuzz::refuse_or_load([&] { scene::load_scene(path); });
    return 0;
}
