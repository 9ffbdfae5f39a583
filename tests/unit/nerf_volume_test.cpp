// A NeRF model file in a `volume` cube, queried directly by the path tracer. The model is built by hand so
// that its field is known in closed form: zero hash-grid features make the density MLP output 0 everywhere
// (no biases), so sigma = exp(0) = 1 per model unit; the colour MLP sees only the constant SH band 0 and a
// direction-dependent band 1 term, so the colour is known for every direction. Expected values are closed
// forms; the march quantises a segment to whole steps of sqrt(3)/1024 model units with a random offset, so a
// single ray's optical depth is off by at most one step (0.0017 here): tolerance 3e-3 relative.
#include <gtest/gtest.h>

#include <cmath>

#include "core/image_io.h"
#include "nerf/model_file.h"
#include "render/scene_data.h"
#include "scene_builders.h"
#include "test_support.h"

namespace npt::render {
namespace {

// sigma = 1 everywhere; colour = sigmoid(a + b * SH1(model x)) per channel, with SH1 = -0.4886 x: looking along
// +model x and -model x gives different colours.
nerf::NerfModel constant_model() {
    nerf::NerfConfig c;
    c.encoding.grid.levels = 2;
    c.encoding.grid.log2_table_size = 10;
    c.encoding.finest_resolution = 32;
    c.occupancy.resolution = 8;
    nerf::NerfModel m = nerf::create_model(c, 1.0f, nerf::ngp_world_to_model(0.33f, Vec3(0.5f)));
    std::fill(m.params.begin(), m.params.end(), 0.0f);
    const nerf::NerfLayout l = m.layout();
    // Colour MLP layer 0: hidden unit 0 = SH0 (input 16: constant 0.2821), unit 1 = relu(SH band 1, x term:
    // input 16 + 3 = -0.4886 x) -- only positive for x < 0.
    float* w0 = m.params.data() + l.color_offset + l.color.layer_offset(0);
    const int in0 = l.color.layer_inputs(0);
    w0[0 * in0 + 16] = 1.0f;
    w0[1 * in0 + 19] = 1.0f;
    // Layer 1: pass both through.
    float* w1 = m.params.data() + l.color_offset + l.color.layer_offset(1);
    const int in1 = l.color.layer_inputs(1);
    w1[0 * in1 + 0] = 1.0f;
    w1[1 * in1 + 1] = 1.0f;
    // Output: r = 2 h0 + 3 h1, g = -h0, b = h0 - 2 h1.
    float* w2 = m.params.data() + l.color_offset + l.color.layer_offset(2);
    const int in2 = l.color.layer_inputs(2);
    w2[0 * in2 + 0] = 2.0f;
    w2[0 * in2 + 1] = 3.0f;
    w2[1 * in2 + 0] = -1.0f;
    w2[2 * in2 + 0] = 1.0f;
    w2[2 * in2 + 1] = -2.0f;
    m.training.reset();
    return m;
}

Rgb expected_linear_colour(const nerf::NerfModel& m, Vec3 model_dir) {
    float sigma = 0;
    Rgb c;
    m.field().query(Vec3(0.5f), model_dir, &sigma, &c);
    return {srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z)};
}

struct Fixture {
    std::filesystem::path dir = test::temp_dir();
    nerf::NerfModel model = constant_model();
    Fixture() { nerf::save_model(dir / "m.npt", model, false); }

    scene::Scene scene(const Mat4& local_to_world, const std::string& extra = "") const {
        scene::Scene s;
        s.source = dir / "scene.gltf";
        scene::VolumeInstance v;
        v.name = "nerf";
        v.local_to_world = local_to_world;
        v.extras_json = R"({"volume": {"file": "m.npt")" + extra + "}}";
        v.declared_in = dir / "scene.gltf";
        s.volumes = {v};
        return s;
    }
};

Rgb trace(const scene::Scene& s, Ray ray) { return test::trace_one_path(s, ray); }

void expect_rgb(Rgb got, Vec3 expected, const char* what) {
    for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(got[k], expected[k], 3e-3 * std::max(expected[k], 1e-2f)) << what << " ch " << k;
}

TEST(NerfVolume, ConstantFieldMatchesClosedFormAndIgnoresNodeScale) {
    Fixture f;
    // Local x runs along model z (nerf_placement.h); the crop (the whole unit cube) spans local [-1, 1]: a ray
    // along local x crosses 1 model unit, so T = exp(-1) whatever the node's scale.
    for (float half : {0.25f, 1.0f, 3.0f}) {
        const scene::Scene s = f.scene(Mat4::scale(half, half, half));
        const Rgb l = trace(s, {{-10.0f, 0.0f, 0.0f}, {1, 0, 0}});
        const float t = std::exp(-1.0f);
        expect_rgb(l, expected_linear_colour(f.model, Vec3(0, 0, 1)) * (1 - t), "along local +x");
    }
    // Looking along local +y = model +x, then -y = model -x: band 1 changes the colour with the direction.
    const scene::Scene s = f.scene(Mat4::identity());
    const Rgb plus = trace(s, {{0.0f, -10.0f, 0.0f}, {0, 1, 0}});
    const Rgb minus = trace(s, {{0.0f, 10.0f, 0.0f}, {0, -1, 0}});
    const float t = std::exp(-1.0f);
    expect_rgb(plus, expected_linear_colour(f.model, Vec3(1, 0, 0)) * (1 - t), "model +x");
    expect_rgb(minus, expected_linear_colour(f.model, Vec3(-1, 0, 0)) * (1 - t), "model -x");
    EXPECT_GT(std::fabs(plus.x - minus.x), 0.05f) << "the colour must depend on the view direction";
}

TEST(NerfVolume, DensityScaleCropAndPartialSegments) {
    Fixture f;
    // density_scale 2: twice the optical depth.
    Rgb l = trace(f.scene(Mat4::identity(), R"(, "density_scale": 2)"), {{-10, 0, 0}, {1, 0, 0}});
    float t = std::exp(-2.0f);
    expect_rgb(l, expected_linear_colour(f.model, Vec3(0, 0, 1)) * (1 - t), "density_scale");
    // Crop half of model z (= local x) onto the cube: the same ray now crosses 0.5 model units.
    l = trace(f.scene(Mat4::identity(), R"(, "crop": {"min": [0, 0, 0.25], "max": [1, 1, 0.75]})"),
              {{-10, 0, 0}, {1, 0, 0}});
    t = std::exp(-0.5f);
    expect_rgb(l, expected_linear_colour(f.model, Vec3(0, 0, 1)) * (1 - t), "crop");
    // A camera inside the cube at local x = 0.5 looking along +x: 0.25 model units to the far face.
    l = trace(f.scene(Mat4::identity()), {{0.5f, 0, 0}, {1, 0, 0}});
    t = std::exp(-0.25f);
    expect_rgb(l, expected_linear_colour(f.model, Vec3(0, 0, 1)) * (1 - t), "from inside");
}

TEST(NerfVolume, ShadowRaysSeeItsTransmittance) {
    Fixture f;
    scene::Scene s = f.scene(Mat4::translation(0, 1, 0) * Mat4::scale(0.25f, 0.25f, 0.25f));
    scene::Material white;
    white.base_color = Rgb(0.5f);
    white.metallic = 0.0f;
    white.specular = 0.0f;
    s.materials = {white};
    scene::Mesh floor;
    floor.name = "floor";
    floor.material = 0;
    floor.positions = {{-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5}};
    floor.indices = {0, 1, 2, 0, 2, 3};
    s.meshes = {floor};
    scene::PunctualLight sun;
    sun.type = scene::PunctualType::Directional;
    sun.direction = Vec3(0, -1, 0);
    sun.intensity = Rgb(2.0f);
    s.lights = {sun};
    // The floor point under the cube, seen from beside it: the sun's shadow ray crosses the cube along local
    // y = model x: 1 model unit.
    const Vec3 p{0.05f, 0.0f, 0.02f}, eye{2.0f, 2.0f, 0.02f};
    const Rgb l = trace(s, {eye, normalize(p - eye)});
    const float lit = 0.5f / 3.14159265f * 2.0f;
    expect_rgb(l, Vec3(lit * std::exp(-1.0f)), "shadowed");
}

}  // namespace
}  // namespace npt::render
