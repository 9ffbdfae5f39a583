// Gives a trained model an object frame (nerf/object_frame.h), as `nerfpt capture` does, so that tests
// outside C++ (the Blender add-on's) can import a model that stands somewhere without running a whole
// capture. The frame is the OBJF section's JSON (docs/formats.md), checked by the model file's own reader.
// Usage: nerfpt_set_object_frame MODEL.npt FRAME.json OUT.npt
#include <cstdio>
#include <exception>
#include <fstream>
#include <nlohmann/json.hpp>

#include "nerf/model_file.h"
#include "nerf/object_frame.h"

int main(int argc, char** argv) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: nerfpt_set_object_frame MODEL.npt FRAME.json OUT.npt\n");
        return 2;
    }
    try {
        npt::nerf::NerfModel model = npt::nerf::load_model(argv[1]);
        std::ifstream in(argv[2]);
        if (!in) {
            std::fprintf(stderr, "nerfpt_set_object_frame: %s: cannot open\n", argv[2]);
            return 1;
        }
        model.object = npt::nerf::object_frame_from_json(nlohmann::json::parse(in), argv[2]);
        npt::nerf::save_model(argv[3], model);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "nerfpt_set_object_frame: %s\n", e.what());
        return 1;
    }
    return 0;
}
