// OptiX against the CPU backend on a scene with a relit NeRF (a relightable model made in code, lit by a sun and
// an environment over a floor it shadows): the per-thread OptiX program runs the same trace_path, free flight and
// event shading, so at the same seed the images must agree within the noise of the paths that diverge (the
// parity statistic of optix_render_test.cpp: the same-seed relMSE below half of two OptiX seeds', image means
// within 0.5%). Registered only where a GPU exists (label gpu).
#include <gtest/gtest.h>

#include <cstdio>

#include "core/image_stats.h"
#include "nerf/model_file.h"
#include "relit_test_fields.h"
#include "render/backend/render_backend.h"
#include "scene/scene.h"
#include "scene_builders.h"
#include "test_support.h"

namespace npt {
namespace {

Image render_on(const scene::Scene& scene, render::RenderOptions o, const std::string& backend) {
    o.backend = backend;
    return render::render_with_backend(scene, render::resolve_options(scene, o));
}

TEST(OptixRelit, RelitNerfMatchesTheCpu) {
    if (!render::optix_backend_built()) GTEST_SKIP() << "built without the OptiX backend";
    const auto dir = test::temp_dir();
    nerf::save_model(dir / "m.npt", test::random_relightable_model(5), false);
    if (!nerf::load_model(dir / "m.npt").relightable())
        GTEST_SKIP() << "the model file does not carry the relight section yet (nerf/model_file.cpp)";

    scene::Scene s;
    s.source = dir / "scene.gltf";
    scene::Material floor_material;
    floor_material.base_color = Rgb(0.7f);
    floor_material.metallic = 0.0f;
    floor_material.roughness = 0.8f;
    s.materials = {floor_material};
    s.meshes = {test::make_quad(Vec3(-3, 0, 3), Vec3(6, 0, 0), Vec3(0, 0, -6), 0)};
    scene::PunctualLight sun;
    sun.type = scene::PunctualType::Directional;
    sun.direction = normalize(Vec3(-0.4f, -1.0f, -0.3f));
    sun.intensity = Rgb(3.0f);
    s.lights = {sun};
    s.environment.color = Rgb(0.2f, 0.25f, 0.3f);
    scene::VolumeInstance v;
    v.name = "nerf";
    v.local_to_world = Mat4::translation(0.0, 0.7, 0.0) * Mat4::scale(0.7, 0.7, 0.7);
    v.declared_in = s.source;
    v.extras_json = R"({"volume": {"file": "m.npt"}})";
    s.volumes = {v};
    scene::Camera cam;
    cam.position = Vec3(0.0f, 1.5f, 3.5f);
    cam.forward = normalize(Vec3(0.0f, 0.7f, 0.0f) - cam.position);
    cam.right = normalize(cross(cam.forward, Vec3(0, 1, 0)));
    cam.up = cross(cam.right, cam.forward);
    s.cameras = {cam};
    s.camera = 0;

    render::RenderOptions o;
    o.width = 96;
    o.height = 72;
    o.spp = 64;
    o.seed = 1;
    const Image g1 = render_on(s, o, "optix"), c1 = render_on(s, o, "cpu");
    o.seed = 2;
    const Image g2 = render_on(s, o, "optix");
    const double same_seed = compare_images(g1, c1).rel_mse, other_seed = compare_images(g1, g2).rel_mse;
    std::printf("relit NeRF: OptiX vs CPU at the same seed %.3g, two OptiX seeds %.3g\n", same_seed, other_seed);
    EXPECT_LT(same_seed, 0.5 * other_seed);
    const ImageComparison cmp = compare_images(average(g1, g2), c1);
    for (size_t k = 0; k < 3; ++k)
        EXPECT_NEAR(cmp.mean_test[k], cmp.mean_ref[k], 0.005 * cmp.mean_ref[k] + 1e-4) << "channel " << k;
}

}  // namespace
}  // namespace npt
