// The same trained NeRF rendered in a scene two ways: queried directly, and baked to an OpenVDB grid in the same
// cube. The baked images must approach the direct one as the bake's resolution grows. Colour is baked for the
// camera's viewing direction (so view dependence is not what is measured). Bounds: the error must fall by at
// least 2x per doubling of the resolution (trilinear reconstruction of a sharp field converges at first order
// at its surfaces) and reach below 2% relMSE at 64^3 for this 32x32-pixel scene; the Monte Carlo noise between
// two seeds of the direct render, measured in the test, must be far below both.
#include <gtest/gtest.h>

#include <fstream>

#include "bake/bake_grid.h"
#include "bake/grid_writers.h"
#include "core/image_stats.h"
#include "nerf/model_file.h"
#include "nerf/trainer.h"
#include "nerf_test_scene.h"
#include "render/renderer.h"
#include "scene/scene.h"
#include "test_support.h"

namespace npt {
namespace {

nerf::NerfModel trained_spheres() {
    const nerf::Dataset train = test::make_sphere_scene({.views = 20, .size = 32, .view_seed = 1});
    nerf::NerfModel m = nerf::create_model(test::small_sphere_config(), 1.0f, nerf::ngp_world_to_model(train.scale, train.offset));
    nerf::Trainer t(m, train);
    for (int i = 0; i < 300; ++i) t.step();
    t.sync_model();
    m.training.reset();
    return m;
}

Image render_with(const std::filesystem::path& dir, const std::string& file, uint64_t seed) {
    const auto scene_path = dir / ("scene_" + file + ".json");
    std::ofstream(scene_path) << R"({"camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "yfov_deg": 50},
        "background": [0.5, 0.5, 0.5], "render": {"width": 48, "height": 48, "spp": 16, "max_depth": 2},
        "volumes": [{"file": ")" << file << R"("}]})";
    const scene::Scene s = scene::load_scene(scene_path);
    render::RenderOptions o;
    o.seed = seed;
    return render::render(s, render::resolve_options(s, o));
}

TEST(BakeRoundTrip, BakedGridConvergesToTheDirectRender) {
    const auto dir = test::temp_dir();
    const nerf::NerfModel model = trained_spheres();
    nerf::save_model(dir / "m.npt", model, false);
    const Image direct = render_with(dir, "m.npt", 1);
    const double noise = compare_images(render_with(dir, "m.npt", 2), direct).rel_mse;
    std::vector<double> errors;
    for (int res : {16, 32, 64}) {
        bake::BakeSettings bs;
        bs.resolution = res;
        bs.direction = Vec3(0, 0, -1);  // the camera looks along -z of the cube (= training-world) axes
        const std::string name = "m_" + std::to_string(res) + ".vdb";
        bake::write_vdb(dir / name, bake::bake_model(model, bs));
        errors.push_back(compare_images(render_with(dir, name, 1), direct).rel_mse);
        std::printf("bake %d^3: relMSE vs direct %.5f (noise between seeds %.6f)\n", res, errors.back(), noise);
    }
    EXPECT_LT(errors[1], 0.5 * errors[0]);
    EXPECT_LT(errors[2], 0.5 * errors[1]);
    EXPECT_LT(errors[2], 0.02);
    EXPECT_LT(noise, 0.1 * errors[2]);
}

}  // namespace
}  // namespace npt
