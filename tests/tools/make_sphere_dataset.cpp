// Writes the NeRF tests' sphere data set (tests/nerf_test_scene.h: three shaded spheres seen from cameras on
// a sphere) as PNG frames + transforms.json, and the small config those tests train with as config.json, so
// that tests outside C++ (the Blender add-on's) can train a model with the nerfpt binary in seconds. Usage:
// nerfpt_make_sphere_dataset OUT_DIR [VIEWS [SIZE]]
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "nerf_test_scene.h"

int main(int argc, char** argv) {
    if (argc < 2 || argc > 4) {
        std::fprintf(stderr, "usage: nerfpt_make_sphere_dataset OUT_DIR [VIEWS [SIZE]]\n");
        return 2;
    }
    try {
        const std::filesystem::path out = argv[1];
        npt::test::SphereSceneOptions o;
        if (argc > 2) o.views = std::atoi(argv[2]);
        if (argc > 3) o.size = std::atoi(argv[3]);
        if (o.views < 1 || o.size < 1) {
            std::fprintf(stderr, "nerfpt_make_sphere_dataset: VIEWS and SIZE must be positive\n");
            return 2;
        }
        npt::test::write_dataset(npt::test::make_sphere_scene(o), out, o.fov_degrees);
        std::ofstream(out / "config.json")
            << npt::nerf::config_to_json(npt::test::small_sphere_config()).dump(2);
        std::printf("wrote %d views of %dx%d and config.json to %s\n", o.views, o.size, o.size, out.c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "nerfpt_make_sphere_dataset: %s\n", e.what());
        return 1;
    }
    return 0;
}
