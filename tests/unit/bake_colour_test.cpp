// A bake keeps the colour the cameras saw (issue 24): a NeRF trained briefly on the sphere scene is rendered
// queried directly and baked with the default colour (`--direction avg`) from four views like the training
// cameras', and the baked object must be as bright as the direct one. The model's colour is only trained for
// (point, direction) pairs a camera saw: averaged over every direction, including ones from below (no camera)
// and from behind the surface (never visible), the bake came out darker or brighter at random. Bound, per
// view set: |sum over object pixels of baked / direct - 1| below the bake's own reconstruction error at this
// resolution (measured: the same grid with the colour baked for each view's exact direction) plus 4 standard
// errors of the ratio from the render noise (measured between two seeds of the direct render).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "bake/bake_grid.h"
#include "bake/grid_writers.h"
#include "nerf/model_file.h"
#include "nerf/trainer.h"
#include "nerf_test_scene.h"
#include "render/renderer.h"
#include "scene/scene.h"
#include "test_support.h"

namespace npt {
namespace {

nerf::NerfModel trained_spheres(const nerf::Dataset& train) {
    nerf::NerfModel m = nerf::create_model(test::small_sphere_config(), 1.0f,
                                           nerf::ngp_world_to_model(train.scale, train.offset));
    nerf::Trainer t(m, train);
    // 1000 steps: at 300 the field was still rough enough that the bound below held or failed with the
    // optimizer's rule (docs/benchmarks.md, "Sparse Adam on the CPU": 1.0148 dense, 1.0718 sparse).
    for (int i = 0; i < 1000; ++i) t.step();
    t.sync_model();
    m.training.reset();
    return m;
}

// Four views around the spheres, 20 degrees above the horizon (the training cameras lie between -17 and 64
// degrees): camera positions in the training world, which is the cube's local frame (unscaled, unrotated).
std::vector<Vec3> view_positions() {
    std::vector<Vec3> eyes;
    for (int a = 0; a < 4; ++a) {
        const float phi = 0.5f * k_pi * float(a) + 0.3f, el = 20.0f * k_pi / 180.0f;
        eyes.push_back(Vec3(std::cos(phi) * std::cos(el), std::sin(phi) * std::cos(el), std::sin(el)) * 3.0f);
    }
    return eyes;
}

Image render_with(const std::filesystem::path& dir, const std::string& file, Vec3 eye, uint64_t seed) {
    const auto scene_path = dir / ("scene_" + file + ".json");
    std::ofstream(scene_path) << "{\"camera\": {\"position\": [" << eye.x << ", " << eye.y << ", " << eye.z
                              << R"(], "look_at": [0, 0, 0], "up": [0, 0, 1], "yfov_deg": 50},
        "background": [0, 0, 0], "render": {"width": 40, "height": 40, "spp": 8, "max_depth": 1},
        "volumes": [{"file": ")" << file << R"("}]})";
    const scene::Scene s = scene::load_scene(scene_path);
    render::RenderOptions o;
    o.seed = seed;
    return render::render(s, render::resolve_options(s, o));
}

// Object pixels of a view: where the direct render is brighter than 5% of its brightest pixel.
std::vector<bool> object_pixels(const Image& direct) {
    float peak = 0.0f;
    for (int y = 0; y < direct.height; ++y)
        for (int x = 0; x < direct.width; ++x) peak = std::max(peak, luminance(direct.rgb(x, y)));
    std::vector<bool> mask;
    for (int y = 0; y < direct.height; ++y)
        for (int x = 0; x < direct.width; ++x) mask.push_back(luminance(direct.rgb(x, y)) > 0.05f * peak);
    return mask;
}

double object_sum(const Image& img, const std::vector<bool>& mask) {
    double s = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            if (mask[size_t(y) * size_t(img.width) + size_t(x)]) {
                const Rgb c = img.rgb(x, y);
                s += double(c.x) + double(c.y) + double(c.z);
            }
    return s;
}

TEST(BakeColour, BakedObjectIsAsBrightAsTheDirectRender) {
    const auto dir = test::temp_dir();
    const nerf::Dataset train = test::make_sphere_scene({.views = 20, .size = 32, .view_seed = 1});
    nerf::NerfModel model = trained_spheres(train);
    model.view_directions = nerf::training_view_directions(train.cameras, model.world_to_model);
    nerf::save_model(dir / "m.npt", model, false);
    constexpr int k_res = 64;
    bake::BakeSettings bs;
    bs.resolution = k_res;
    bake::write_vdb(dir / "avg.vdb", bake::bake_model(model, bs));

    double direct = 0, direct2 = 0, baked = 0, exact_dir = 0;
    const std::vector<Vec3> eyes = view_positions();
    for (size_t v = 0; v < eyes.size(); ++v) {
        const Image d = render_with(dir, "m.npt", eyes[v], 1);
        const std::vector<bool> mask = object_pixels(d);
        direct += object_sum(d, mask);
        direct2 += object_sum(render_with(dir, "m.npt", eyes[v], 2), mask);
        baked += object_sum(render_with(dir, "avg.vdb", eyes[v], 1), mask);
        // The same bake with the colour of this view's direction (towards the origin): what the grid itself
        // costs, with no direction averaging at all.
        bake::BakeSettings view_bs = bs;
        view_bs.direction = normalize(-eyes[v]);
        const std::string name = "view" + std::to_string(v) + ".vdb";
        bake::write_vdb(dir / name, bake::bake_model(model, view_bs));
        exact_dir += object_sum(render_with(dir, name, eyes[v], 1), mask);
    }
    const double ratio = baked / direct, grid_error = std::abs(exact_dir / direct - 1.0);
    // Two seeds differ by sqrt(2) standard errors of one render's object sum; the ratio's error is that of
    // the direct render and the baked one together (independent), sqrt(2) of one.
    const double noise = std::abs(direct2 / direct - 1.0);
    std::printf("baked/direct %.4f, exact-direction bake/direct %.4f, seed-to-seed %.5f\n", ratio,
                exact_dir / direct, direct2 / direct);
    EXPECT_LT(std::abs(ratio - 1.0), grid_error + 4.0 * noise + 1e-3);
}

}  // namespace
}  // namespace npt
