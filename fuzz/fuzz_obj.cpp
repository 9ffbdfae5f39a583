// Wavefront OBJ + MTL (scene/obj_loader.h). The input is the OBJ text, optionally followed by a line "#MTL"
// and the text of in.mtl (which the OBJ names with "mtllib in.mtl").
#include <string_view>

#include "harness_support.h"
#include "scene/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace npt;
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    const size_t split = text.find("\n#MTL\n");
    fuzz::put("in.mtl", split == std::string_view::npos ? std::string_view() : text.substr(split + 6));
    const auto path = fuzz::put("in.obj", text.substr(0, split));
    fuzz::refuse_or_load([&] { scene::load_scene(path); });
    return 0;
}
