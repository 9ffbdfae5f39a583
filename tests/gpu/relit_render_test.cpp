// OptiX against the CPU backend on a scene with a relit NeRF (a relightable model made in code, with the network
// the NeRF pass's fp16 kernels take, lit by a sun and an environment over a floor it shadows), in both forms of
// the OptiX renderer. The per-thread program runs the CPU's trace_path, free flight and event shading; the
// wavefront form has the NeRF pass sample the free flights and the shadow rays' transmittance (fp16 densities) and
// shades the events in its launches. At the same seed the images must agree within the noise of the paths that
// diverge (the parity statistic of optix_render_test.cpp: the same-seed relMSE below half of two OptiX seeds',
// image means within 0.5%), the colour and the albedo AOV (the camera vertex's first event, record_first_event).
// What the fp16 densities cost: they move an event by a sample where the target lies within their rounding of a
// sample's optical depth, and such a path goes on from a neighbouring point (then, in general, elsewhere); the
// same-seed relMSE printed for both forms measures it. Registered only where a GPU exists (label gpu).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "core/image_stats.h"
#include "nerf/cuda/fused_mlp.h"
#include "nerf/model_file.h"
#include "relit_test_fields.h"
#include "render/backend/render_backend.h"
#include "scene/scene.h"
#include "scene_builders.h"
#include "test_support.h"

namespace npt {
namespace {

struct Render {
    Image image;
    render::AovImages aovs;  // the albedo
};

Render render_on(const scene::Scene& scene, render::RenderOptions o, const std::string& backend) {
    o.backend = backend;
    o.aovs = render::k_aov_albedo;
    Render r;
    r.image = render::render_with_backend(scene, render::resolve_options(scene, o), {}, nullptr, &r.aovs);
    return r;
}

// g1 and c1 at the same seed, g2 at another: the parity statistic of optix_render_test.cpp's expect_same_as_cpu.
void expect_same_as_cpu(const Image& g1, const Image& g2, const Image& c1, const std::string& what) {
    const double same_seed = compare_images(g1, c1).rel_mse, other_seed = compare_images(g1, g2).rel_mse;
    std::printf("relit NeRF, %s: OptiX vs CPU at the same seed %.3g, two OptiX seeds %.3g\n", what.c_str(), same_seed,
                other_seed);
    EXPECT_LT(same_seed, 0.5 * other_seed) << what;
    const ImageComparison cmp = compare_images(average(g1, g2), c1);
    for (size_t k = 0; k < 3; ++k)
        EXPECT_NEAR(cmp.mean_test[k], cmp.mean_ref[k], 0.005 * cmp.mean_ref[k] + 1e-4) << what << " channel " << k;
}

// NERFPT_OPTIX_WAVEFRONT=0 (the per-thread program) while it lives.
struct PerThreadForm {
    PerThreadForm() { setenv("NERFPT_OPTIX_WAVEFRONT", "0", 1); }
    ~PerThreadForm() { unsetenv("NERFPT_OPTIX_WAVEFRONT"); }
    PerThreadForm(const PerThreadForm&) = delete;
    PerThreadForm& operator=(const PerThreadForm&) = delete;
};

TEST(OptixRelit, RelitNerfMatchesTheCpuInBothForms) {
    if (!render::optix_backend_built()) GTEST_SKIP() << "built without the OptiX backend";
    const auto dir = test::temp_dir();
    const nerf::NerfModel model = test::random_relightable_model(5, true, true);
    std::string why;
    ASSERT_TRUE(nerf::cuda::mlp_shape_supported(model.layout(), &why)) << "the NeRF pass would not take it: " << why;
    nerf::save_model(dir / "m.npt", model, false);
    ASSERT_TRUE(nerf::load_model(dir / "m.npt").relightable());

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
    const Render c1 = render_on(s, o, "cpu");
    for (const bool wavefront : {true, false}) {
        const std::string form = wavefront ? "wavefront" : "per thread";
        SCOPED_TRACE(form);
        std::unique_ptr<PerThreadForm> per_thread;
        if (!wavefront) per_thread = std::make_unique<PerThreadForm>();
        o.seed = 1;
        const Render g1 = render_on(s, o, "optix");
        o.seed = 2;
        const Render g2 = render_on(s, o, "optix");
        expect_same_as_cpu(g1.image, g2.image, c1.image, form + ", colour");
        expect_same_as_cpu(g1.aovs.albedo, g2.aovs.albedo, c1.aovs.albedo, form + ", albedo AOV");
    }
}

}  // namespace
}  // namespace npt
