// The object frame a capture stores in its model (nerf/object_frame.h): the OBJF section's round trip and bad
// input, and the placement it gives a `volume` cube: with an identity node the object's box stands on y = 0
// around the origin, at object scale, Y up, whatever the model's own orientation. The model is built by hand
// with all parameters zero: sigma = exp(0) = 1 per model unit and colour sigmoid(0) = 0.5 (sRGB) everywhere, so
// a ray's radiance is c (1 - exp(-length in model units)) in closed form (the march's step quantisation: 3e-3
// (the march's steps of sqrt(3)/1024 model units from a random offset: the optical depth is off by at most one).
#include "nerf/object_frame.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/rng.h"
#include "core/srgb.h"
#include "nerf/model_file.h"
#include "nerf/render_view.h"
#include "scene_builders.h"
#include "test_support.h"

namespace npt::nerf {
namespace {

// Object space in metres -> the training world: 2.5 world units per metre (a capture in its own units), up
// tilted 20 degrees about world x, the base at (0.1, 0.2, -0.3).
ObjectFrame tilted_frame() {
    ObjectFrame f;
    const double a = 20.0 * 3.14159265358979 / 180.0;
    Mat4 rot;
    rot.m = {{{1, 0, 0, 0}, {0, std::cos(a), -std::sin(a), 0}, {0, std::sin(a), std::cos(a), 0}, {0, 0, 0, 1}}};
    f.object_to_world = Mat4::translation(0.1, 0.2, -0.3) * rot * Mat4::scale(2.5, 2.5, 2.5);
    f.box_min = Vec3(-0.1f, -0.15f, 0.0f);
    f.box_max = Vec3(0.1f, 0.15f, 0.3f);
    f.metric = true;
    return f;
}

NerfModel zero_model() {
    NerfConfig c;
    c.encoding.grid.levels = 2;
    c.encoding.grid.log2_table_size = 10;
    c.encoding.finest_resolution = 32;
    c.occupancy.resolution = 8;
    NerfModel m = create_model(c, 1.0f, ngp_world_to_model(0.33f, Vec3(0.5f)));
    std::fill(m.params.begin(), m.params.end(), 0.0f);
    m.training.reset();
    return m;
}

TEST(ObjectFrame, SectionRoundTripsAndOldModelsHaveNone) {
    const auto dir = test::temp_dir();
    NerfModel m = zero_model();
    save_model(dir / "plain.npt", m, false);
    EXPECT_FALSE(load_model(dir / "plain.npt").object.has_value());
    m.object = tilted_frame();
    save_model(dir / "object.npt", m, false);
    const NerfModel back = load_model(dir / "object.npt");
    ASSERT_TRUE(back.object.has_value());
    for (size_t r = 0; r < 4; ++r)
        for (size_t c = 0; c < 4; ++c)
            EXPECT_DOUBLE_EQ(back.object->object_to_world.m[r][c], m.object->object_to_world.m[r][c]);
    EXPECT_EQ(back.object->box_min.y, -0.15f);
    EXPECT_EQ(back.object->box_max.z, 0.3f);
    EXPECT_TRUE(back.object->metric);
    EXPECT_FALSE(back.object->object_only);
    EXPECT_FALSE(object_frame_to_json(*back.object).contains("object_only"));  // older readers see what they know
    EXPECT_NEAR(back.object->units_per_world(), 0.4, 1e-12);
    m.object->object_only = true;  // an isolated model
    save_model(dir / "isolated.npt", m, false);
    EXPECT_TRUE(load_model(dir / "isolated.npt").object->object_only);
}

TEST(ObjectFrame, BadSectionsAreOneLineErrors) {
    const nlohmann::json good = object_frame_to_json(tilted_frame());
    EXPECT_NO_THROW(object_frame_from_json(good, "m.npt: section 'OBJF'"));
    const auto with = [&](const char* key, nlohmann::json value) {
        nlohmann::json j = good;
        j[key] = std::move(value);
        return j;
    };
    const std::string where = "m.npt: section 'OBJF'";
    test::expect_error_message([&] { object_frame_from_json(with("version", 2), where); }, {where, "'version'"});
    test::expect_error_message([&] { object_frame_from_json(with("object_to_world", {1, 2}), where); },
                               {where, "'object_to_world'", "16 numbers"});
    nlohmann::json mirrored = good;
    mirrored["object_to_world"][0] = -2.5;  // x flipped: a mirror
    test::expect_error_message([&] { object_frame_from_json(mirrored, where); }, {"no mirroring"});
    nlohmann::json sheared = good;
    sheared["object_to_world"][1] = 0.1;
    test::expect_error_message([&] { object_frame_from_json(sheared, where); }, {"uniform scale"});
    nlohmann::json empty_box = good;
    empty_box["box"]["max"][2] = 0.0;
    test::expect_error_message([&] { object_frame_from_json(empty_box, where); }, {"'box'", "max must exceed"});
    test::expect_error_message([&] { object_frame_from_json(with("object_only", "yes"), where); },
                               {where, "'object_only'", "true or false"});
    nlohmann::json nan = good;
    nan["box"]["min"][0] = "x";
    test::expect_error_message([&] { object_frame_from_json(nan, where); }, {"'min'", "finite"});
    // A model refuses to save an invalid frame rather than writing one no reader accepts.
    NerfModel m = zero_model();
    m.object = tilted_frame();
    m.object->box_max.x = -1.0f;
    const auto dir = test::temp_dir();
    test::expect_error_message([&] { save_model(dir / "bad.npt", m, false); }, {"model not saved", "'box'"});
}

// The local -> model map is the frame: local origin = the base centre, local +y = the object's up.
TEST(ObjectFrame, LocalSpaceIsTheObjectFrameTurnedYUp) {
    const ObjectFrame f = tilted_frame();
    const Mat4 w2m = ngp_world_to_model(0.33f, Vec3(0.5f));
    const LocalToModel l = object_local_to_model(f, w2m);
    const auto model_of_object = [&](Vec3 o) { return w2m.transform_point(f.object_to_world.transform_point(o)); };
    test::expect_near(l.point(Vec3(0, 0, 0)), model_of_object(Vec3(0, 0, 0)));
    test::expect_near(l.point(Vec3(0, 0.3f, 0)), model_of_object(Vec3(0, 0, 0.3f)));      // up
    test::expect_near(l.point(Vec3(0.1f, 0, 0)), model_of_object(Vec3(0.1f, 0, 0)));      // x stays x
    test::expect_near(l.point(Vec3(0, 0, -0.15f)), model_of_object(Vec3(0, 0.15f, 0)));   // -z = object y
    const Vec3 p(0.03f, -0.2f, 0.07f);
    test::expect_near(l.inverse_point(l.point(p)), p, 1e-5f);
    // L^T is the transpose: dot(L^T n, v) = dot(n, L v).
    const Vec3 n(0.3f, -0.1f, 0.7f), v(0.2f, 0.5f, -0.4f);
    EXPECT_NEAR(dot(l.transpose_vector(n), v), dot(n, l.vector(v)), 1e-6f);
    Vec3 lo, hi;
    object_local_box(f, &lo, &hi);
    test::expect_near(lo, Vec3(-0.1f, 0.0f, -0.15f));
    test::expect_near(hi, Vec3(0.1f, 0.3f, 0.15f));
}

struct Placed {
    std::filesystem::path dir = test::temp_dir();
    NerfModel model = zero_model();
    Placed() {
        model.object = tilted_frame();
        save_model(dir / "m.npt", model, false);
    }
    scene::Scene scene(const Mat4& local_to_world, const std::string& extra = "") const {
        scene::Scene s;
        s.source = dir / "scene.gltf";
        scene::VolumeInstance v;
        v.name = "object";
        v.local_to_world = local_to_world;  // the cube's mesh stays [-1, 1]^3: object placement ignores it
        v.extras_json = R"({"volume": {"file": "m.npt")" + extra + "}}";
        v.declared_in = dir / "scene.gltf";
        s.volumes = {v};
        return s;
    }
};

// Model units per metre of the object: 0.33 (instant-ngp's scale) x 2.5 world units per metre.
constexpr float k_model_per_metre = 0.33f * 2.5f;

float radiance(float metres) {
    return srgb_to_linear(0.5f) * (1.0f - std::exp(-metres * k_model_per_metre));
}

void expect_luminance(Rgb got, float expected, const char* what) {
    // One march step of optical depth, sqrt(3)/1024 model units, changes the radiance by at most c times it.
    const float step = srgb_to_linear(0.5f) * 1.7321f / 1024.0f;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], expected, step + 1e-4f) << what;
}

TEST(ObjectFrame, IdentityNodeStandsTheObjectOnTheGroundAtTheOrigin) {
    const Placed p;
    const scene::Scene s = p.scene(Mat4::identity());
    // Across the box at mid-height along x (0.2 m), along z (0.3 m), down through it (0.3 m).
    expect_luminance(test::trace_one_path(s, {{-10, 0.15f, 0}, {1, 0, 0}}), radiance(0.2f), "along x");
    expect_luminance(test::trace_one_path(s, {{0, 0.15f, 10}, {0, 0, -1}}), radiance(0.3f), "along z");
    expect_luminance(test::trace_one_path(s, {{0.05f, 10, 0.05f}, {0, -1, 0}}), radiance(0.3f), "down");
    // Nothing below the ground, above the top or beside the box, although the model's field is everywhere.
    for (const Ray r : {Ray{{-10, -0.01f, 0}, {1, 0, 0}}, Ray{{-10, 0.31f, 0}, {1, 0, 0}},
                        Ray{{0.11f, 10, 0}, {0, -1, 0}}, Ray{{0, 10, 0.16f}, {0, -1, 0}}})
        expect_luminance(test::trace_one_path(s, r), 0.0f, "outside the object's box");
}

TEST(ObjectFrame, TheNodePlacesAndScalesTheObject) {
    const Placed p;
    // Moved to (2, 1, 0) and twice as large: the box spans y 1..1.6 there; sigma stays per model unit, so the
    // same model-space path gives the same radiance.
    const scene::Scene s = p.scene(Mat4::translation(2, 1, 0) * Mat4::scale(2, 2, 2));
    expect_luminance(test::trace_one_path(s, {{-10, 1.3f, 0}, {1, 0, 0}}), radiance(0.2f), "moved, scaled");
    expect_luminance(test::trace_one_path(s, {{-10, 0.99f, 0}, {1, 0, 0}}), 0.0f, "below the moved base");
}

TEST(ObjectFrame, BoxPlacementAndCropStillWorkAndConflictsAreErrors) {
    const Placed p;
    // "placement": "box": the old rule, the model's whole box onto the cube, local x along model z: 1 model unit.
    const scene::Scene box = p.scene(Mat4::identity(), R"(, "placement": "box")");
    const float full = srgb_to_linear(0.5f) * (1.0f - std::exp(-1.0f));
    expect_luminance(test::trace_one_path(box, {{-10, 0, 0}, {1, 0, 0}}), full, "box placement");
    // A crop implies the box placement.
    const scene::Scene crop = p.scene(Mat4::identity(), R"(, "crop": {"min": [0, 0, 0], "max": [1, 1, 1]})");
    expect_luminance(test::trace_one_path(crop, {{-10, 0, 0}, {1, 0, 0}}), full, "crop");
    // "object" with a crop, or on a model without a frame, is an error naming the node and the field.
    test::expect_error_message(
        [&] {
            test::trace_one_path(
                p.scene(Mat4::identity(), R"(, "placement": "object", "crop": {"min": [0, 0, 0], "max": [1, 1, 1]})"),
                {{-10, 0, 0}, {1, 0, 0}});
        },
        {"node 'object'", "extras.volume.crop"});
    NerfModel plain = zero_model();
    save_model(p.dir / "plain.npt", plain, false);
    scene::Scene s = p.scene(Mat4::identity(), R"(, "placement": "object")");
    s.volumes[0].extras_json = R"({"volume": {"file": "plain.npt", "placement": "object"}})";
    test::expect_error_message([&] { test::trace_one_path(s, {{-10, 0, 0}, {1, 0, 0}}); },
                               {"extras.volume.placement", "plain.npt"});
    test::expect_error_message(
        [&] { test::trace_one_path(p.scene(Mat4::identity(), R"(, "placement": "up")"), {{-10, 0, 0}, {1, 0, 0}}); },
        {"extras.volume.placement", "\"object\" or \"box\""});
}


// The float test both view renderers use (object_cut.h) agrees with the double-precision transform of
// model_to_object, except within 1e-5 object units of a face (float rounding).
TEST(ObjectFrame, ObjectCutIsTheBoxTestOfModelToObject) {
    const NerfModel model = [] {
        NerfModel m = zero_model();
        m.object = tilted_frame();
        return m;
    }();
    const ObjectCut cut = object_cut(*model.object, model.world_to_model);
    const Mat4 to_object = model_to_object(*model.object, model.world_to_model);
    EXPECT_FALSE(ObjectCut{}.outside(Vec3(5.0f, 5.0f, 5.0f)));  // inactive: nothing is cut
    Pcg32 rng(3, 1);
    int inside = 0, outside = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3 p(rng.next_float(), rng.next_float(), rng.next_float());
        const Vec3 o = to_object.transform_point(p);
        const Vec3 lo = model.object->box_min, hi = model.object->box_max;
        const double margin = std::min({o.x - lo.x, o.y - lo.y, o.z - lo.z, hi.x - o.x, hi.y - o.y, hi.z - o.z});
        if (std::abs(margin) < 1e-5) continue;
        EXPECT_EQ(cut.outside(p), margin < 0) << "model point " << p.x << ", " << p.y << ", " << p.z;
        (margin < 0 ? outside : inside) += 1;
    }
    EXPECT_GT(inside, 100);  // both sides were tried
    EXPECT_GT(outside, 100);
}

// `nerfpt eval --object`: the view renderer sees only the object box. A camera 1 m from the box's centre along
// object -x, looking along +x: its central ray crosses the box's 0.2 m (alpha 1 - exp(-0.2 x 0.825 model
// units)); a corner ray (24 degrees off) misses the box, so it sees nothing, though the whole model covers it.
TEST(ObjectFrame, TheViewRendererCanSeeTheObjectAlone) {
    NerfModel model = zero_model();
    model.object = tilted_frame();
    const Mat4& o2w = model.object->object_to_world;
    auto world_dir = [&](Vec3 v) { return normalize(o2w.transform_vector(v)); };
    const Vec3 x = world_dir(Vec3(0, -1, 0)), y = world_dir(Vec3(0, 0, 1)), z = world_dir(Vec3(-1, 0, 0));
    const Vec3 eye = o2w.transform_point(Vec3(-1.0f, 0.0f, 0.15f));
    Camera cam;
    cam.camera_to_world.m = {{{x.x, y.x, z.x, eye.x}, {x.y, y.y, z.y, eye.y}, {x.z, y.z, z.z, eye.z}, {0, 0, 0, 1}}};
    cam.width = cam.height = 9;
    cam.fx = cam.fy = 9.0f;
    cam.cx = cam.cy = 4.5f;
    ViewOptions whole, object;
    object.object_only = true;
    const Image all = render_view(model, cam, whole), alone = render_view(model, cam, object);
    auto alpha = [](const Image& img, int px, int py) { return img.pixels[(size_t(py) * 9 + px) * 4 + 3]; };
    const float step = 1.7321f / 1024.0f;  // one march step of optical depth
    EXPECT_NEAR(alpha(alone, 4, 4), 1.0f - std::exp(-0.2f * k_model_per_metre), step + 1e-4f);
    EXPECT_GT(alpha(all, 4, 4), alpha(alone, 4, 4) + 0.1f);
    EXPECT_GT(alpha(all, 0, 0), 0.1f);
    EXPECT_EQ(alpha(alone, 0, 0), 0.0f);
    // A model marked object_only (an isolated one) renders its object alone without being asked.
    NerfModel isolated = model;
    isolated.object->object_only = true;
    const Image marked = render_view(isolated, cam, whole);
    EXPECT_EQ(marked.pixels, alone.pixels);
    // A model without an object frame cannot be asked for its object.
    NerfModel plain = zero_model();
    test::expect_error_message([&] { render_view(plain, cam, object); }, {"no object frame"});
}

}  // namespace
}  // namespace npt::nerf
