// glTF animation: each interpolation against values computed by hand, a parent-child chain, the loader's
// bindings (a moving camera, mesh, light and volume cube follow their nodes; static ones are not rewritten),
// and bad input that must fail with one line naming the file and the field.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "gltf_builder.h"
#include "scene/animation.h"
#include "scene/scene.h"
#include "test_support.h"

namespace npt::scene {
namespace {

using nlohmann::json;
using test::Builder;
using test::expect_near;
namespace fs = std::filesystem;

constexpr double k_tol = 1e-12;
const double k_pi_d = std::acos(-1.0);  // core/vec.h's k_pi is a float

AnimationChannel channel(AnimationPath path, Interpolation interp, std::vector<double> times,
                         std::vector<double> values) {
    AnimationChannel c;
    c.node = 0;
    c.path = path;
    c.interpolation = interp;
    c.times = std::move(times);
    c.values = std::move(values);
    return c;
}

TEST(Animation, StepHoldsEachKeyUntilTheNext) {
    const auto c = channel(AnimationPath::Translation, Interpolation::Step, {0, 1, 2}, {0, 0, 0, 1, 2, 3, 4, 5, 6});
    EXPECT_EQ(sample_channel(c, -1.0)[1], 0.0);  // before the first key: the first value
    EXPECT_EQ(sample_channel(c, 0.5)[1], 0.0);
    EXPECT_EQ(sample_channel(c, 1.0)[1], 2.0);
    EXPECT_EQ(sample_channel(c, 1.999)[2], 3.0);
    EXPECT_EQ(sample_channel(c, 7.0)[0], 4.0);  // after the last: the last
}

TEST(Animation, LinearTranslationAndScale) {
    const auto t = channel(AnimationPath::Translation, Interpolation::Linear, {1, 3}, {0, 0, 0, 4, 8, -4});
    const auto v = sample_channel(t, 1.5);  // u = 0.25
    EXPECT_NEAR(v[0], 1.0, k_tol);
    EXPECT_NEAR(v[1], 2.0, k_tol);
    EXPECT_NEAR(v[2], -1.0, k_tol);
    const auto s = channel(AnimationPath::Scale, Interpolation::Linear, {0, 1}, {1, 1, 1, 3, 1, 2});
    EXPECT_NEAR(sample_channel(s, 0.5)[0], 2.0, k_tol);
    EXPECT_NEAR(sample_channel(s, 0.5)[2], 1.5, k_tol);
}

TEST(Animation, LinearRotationIsSlerpOnTheShorterArc) {
    // Identity to 90 degrees about Z over 3 s: at 1 s, 30 degrees (a lerp of the quaternions would give 28.9).
    const double h = std::sqrt(0.5);
    auto c = channel(AnimationPath::Rotation, Interpolation::Linear, {0, 3}, {0, 0, 0, 1, 0, 0, h, h});
    auto q = sample_channel(c, 1.0);
    EXPECT_NEAR(q[2], std::sin(k_pi_d / 12), 1e-12);  // half of 30 degrees
    EXPECT_NEAR(q[3], std::cos(k_pi_d / 12), 1e-12);
    // The same end rotation written as -q: the shorter arc gives the same 30 degrees (up to sign).
    c.values = {0, 0, 0, 1, 0, 0, -h, -h};
    q = sample_channel(c, 1.0);
    EXPECT_NEAR(std::abs(q[2]), std::sin(k_pi_d / 12), 1e-12);
    EXPECT_NEAR(std::abs(q[3]), std::cos(k_pi_d / 12), 1e-12);
    EXPECT_GT(q[2] * q[3], 0.0);
}

TEST(Animation, CubicSplineIsTheSpecsHermite) {
    // Keys at 0 s and 2 s (dt = 2), values 0 and 1, out-tangent of key 0 = 1 /s, in-tangent of key 1 = 0.
    // u = 0.5: h00 = 0.5, h10 = 0.125, h01 = 0.5, h11 = -0.125 -> 0.125 * 2 * 1 + 0.5 * 1 = 0.75.
    // u = 0.25: h10 = 0.140625, h01 = 0.15625 -> 0.140625 * 2 + 0.15625 = 0.4375.
    const auto c = channel(AnimationPath::Translation, Interpolation::CubicSpline, {0, 2},
                           {/*in*/ 9, 9, 9, /*value*/ 0, 0, 0, /*out*/ 1, 0, 0,
                            /*in*/ 0, 0, 0, /*value*/ 1, 0, 0, /*out*/ 9, 9, 9});
    EXPECT_NEAR(sample_channel(c, 1.0)[0], 0.75, k_tol);
    EXPECT_NEAR(sample_channel(c, 0.5)[0], 0.4375, k_tol);
    EXPECT_NEAR(sample_channel(c, 2.0)[0], 1.0, k_tol);  // the key's value, not its tangents
    EXPECT_NEAR(sample_channel(c, 0.0)[0], 0.0, k_tol);
}

TEST(Animation, CubicSplineRotationIsNormalised) {
    const double h = std::sqrt(0.5);
    const auto c = channel(AnimationPath::Rotation, Interpolation::CubicSpline, {0, 1},
                           {0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, h, h, 0, 0, 0, 0});
    const auto q = sample_channel(c, 0.5);  // h00 = h01 = 0.5: (0, 0, h/2, (1+h)/2), normalised
    const double n = std::sqrt(0.25 * h * h + 0.25 * (1 + h) * (1 + h));
    EXPECT_NEAR(q[2], 0.5 * h / n, 1e-12);
    EXPECT_NEAR(q[3], 0.5 * (1 + h) / n, 1e-12);
}

TEST(Animation, ParentChildChain) {
    // Parent: translation (2,0,0), rotating 0 -> 90 degrees about Z over 1 s. Child: translation (1,0,0) at rest,
    // scale 1 -> 3 over 1 s. At 1 s the child's origin is (2,0,0) + Rz90 (1,0,0) = (2,1,0), its x axis
    // Rz90 (3,0,0) = (0,3,0); at 0.5 s its origin is (2 + cos 45, sin 45, 0).
    std::vector<AnimationNode> nodes(2);
    nodes[0].translation = {2, 0, 0};
    nodes[1].parent = 0;
    nodes[1].translation = {1, 0, 0};
    const double h = std::sqrt(0.5);
    Animation a;
    a.channels.push_back(channel(AnimationPath::Rotation, Interpolation::Linear, {0, 1}, {0, 0, 0, 1, 0, 0, h, h}));
    a.channels.push_back(channel(AnimationPath::Scale, Interpolation::Linear, {0, 1}, {1, 1, 1, 3, 3, 3}));
    a.channels[1].node = 1;
    auto w = world_transforms(nodes, &a, 1.0);
    expect_near(w[1].transform_point(Vec3(0.0f)), Vec3(2, 1, 0));
    expect_near(w[1].transform_vector(Vec3(1, 0, 0)), Vec3(0, 3, 0));
    w = world_transforms(nodes, &a, 0.5);
    expect_near(w[1].transform_point(Vec3(0.0f)), Vec3(float(2 + h), float(h), 0));
    // A placement (a JSON scene's include) goes above the roots.
    w = world_transforms(nodes, &a, 1.0, Mat4::translation(0, 0, 5));
    expect_near(w[1].transform_point(Vec3(0.0f)), Vec3(2, 1, 5));
    // No animation: the rest pose.
    w = world_transforms(nodes, nullptr, 1.0);
    expect_near(w[1].transform_point(Vec3(0.0f)), Vec3(3, 0, 0));
}

TEST(Animation, FrameTimeIsBlendersMapping) { EXPECT_DOUBLE_EQ(frame_time(48, 24), 2.0); }

// A file with a camera under an animated rig, a moving triangle, a static triangle, a moving light and a moving
// volume cube: the loader binds the moving ones and pose_scene moves exactly those.
struct AnimatedFile {
    Builder b;
    int times = -1;
    AnimatedFile() {
        const int tri = b.triangle(-1, "tri");
        b.j["materials"] = json::array({{{"name", "volume"}}});
        const int cube = b.triangle(0, "cube");
        b.j["cameras"] = json::array({{{"type", "perspective"}, {"perspective", {{"yfov", 0.5}, {"znear", 0.1}}}}});
        b.j["extensions"]["KHR_lights_punctual"]["lights"] = json::array({{{"type", "point"}, {"intensity", 1.0}}});
        const int cam = b.node({{"name", "cam"}, {"camera", 0}, {"translation", {0, 0, 5}}}, false);
        b.node({{"name", "rig"}, {"children", {cam}}});                                  // node 1
        b.node({{"name", "mover"}, {"mesh", tri}});                                      // node 2
        b.node({{"name", "still"}, {"mesh", tri}, {"translation", {0, 0, -3}}});        // node 3
        b.node({{"name", "lamp"}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});  // node 4
        b.node({{"name", "box"}, {"mesh", cube}, {"extras", {{"volume", {{"file", "x.vdb"}}}}}});  // node 5
        times = b.floats({0, 2}, "SCALAR");
        add_channel(1, "translation", "LINEAR", b.floats({0, 0, 0, 4, 0, 0}, "VEC3"));
        add_channel(2, "translation", "LINEAR", b.floats({0, 0, 0, 0, 2, 0}, "VEC3"));
        add_channel(4, "translation", "STEP", b.floats({0, 0, 0, 0, 0, 7}, "VEC3"));
        add_channel(5, "scale", "LINEAR", b.floats({1, 1, 1, 3, 3, 3}, "VEC3"));
    }
    void add_channel(int node, const char* path, const char* interp, int output, int anim = 0) {
        json& a = b.j["animations"][size_t(anim)];
        a["samplers"].push_back({{"input", times}, {"output", output}, {"interpolation", interp}});
        a["channels"].push_back({{"sampler", a["samplers"].size() - 1}, {"target", {{"node", node}, {"path", path}}}});
    }
};

TEST(Animation, LoadedSceneFollowsItsNodes) {
    AnimatedFile f;
    f.b.j["scenes"][0]["extras"] = {{"fps", 30}};
    Scene s = load_scene(f.b.write("anim.gltf"));
    ASSERT_TRUE(s.animation);
    EXPECT_EQ(s.settings.fps, 30.0);
    EXPECT_EQ(s.animation->meshes.size(), 1u);  // the mover only; the still triangle is not rewritten
    EXPECT_EQ(s.animation->animation.end, 2.0);
    PoseChanges c = pose_scene(s, 1.0);
    expect_near(s.cameras[0].position, Vec3(2, 0, 5));
    ASSERT_EQ(c.meshes.size(), 1u);
    expect_near(s.meshes[c.meshes[0]].positions[1], Vec3(1, 1, 0));
    EXPECT_TRUE(c.cameras);
    EXPECT_FALSE(c.lights);  // STEP: still at the first key
    EXPECT_TRUE(c.volumes);
    EXPECT_NEAR(s.volumes[0].local_to_world.m[0][0], 2.0, 1e-12);
    c = pose_scene(s, 1.0);  // the same time again: nothing moves
    EXPECT_FALSE(c.any());
    c = pose_scene(s, 2.0);
    EXPECT_TRUE(c.lights);
    expect_near(s.lights[0].position, Vec3(0, 0, 7));
}

TEST(Animation, ChoosesByName) {
    AnimatedFile f;
    f.b.j["animations"][0]["name"] = "walk";
    f.add_channel(2, "translation", "LINEAR", f.b.floats({0, 0, 0, 0, 0, 8}, "VEC3"), 1);
    f.b.j["animations"][1]["name"] = "jump";
    LoadOptions opt;
    opt.animation_name = "jump";
    Scene s = load_scene(f.b.write("two.gltf"), opt);
    pose_scene(s, 2.0);
    expect_near(s.cameras[0].position, Vec3(0, 0, 5));  // "jump" does not move the rig
    expect_near(s.meshes[0].positions[0], Vec3(0, 0, 8));
    opt.animation_name = "run";
    test::expect_error_message([&] { load_scene(f.b.write("two.gltf"), opt); },
                               {"two.gltf", "--animation 'run' not found", "'walk'", "'jump'"});
}

void expect_bad(AnimatedFile& f, std::initializer_list<std::string> parts) {
    const fs::path p = f.b.write("bad_anim.gltf");
    test::expect_error_message([&] { load_scene(p); }, parts);
}

TEST(Animation, BadInputIsOneLineNamingTheField) {
    {
        AnimatedFile f;
        f.b.j["animations"][0]["samplers"][0]["input"] = f.b.floats({0, 2, 2}, "SCALAR");
        expect_bad(f, {"bad_anim.gltf", "animations[0].samplers[0].input", "increase strictly"});
    }
    {
        AnimatedFile f;
        f.b.j["animations"][0]["samplers"][0]["input"] = f.b.floats({0, NAN}, "SCALAR");
        expect_bad(f, {"animations[0].samplers[0].input", "not finite"});
    }
    {
        AnimatedFile f;
        f.b.j["animations"][0]["samplers"][1]["output"] = f.b.floats({0, 0, 0, 0, NAN, 0}, "VEC3");
        expect_bad(f, {"animations[0].samplers[1].output", "element 1 is not finite"});
    }
    {
        AnimatedFile f;
        f.b.j["animations"][0]["samplers"][1]["output"] = f.b.floats({0, 0, 0}, "VEC3");
        expect_bad(f, {"animations[0].samplers[1].output", "has 1 elements, expected 2"});
    }
    {
        AnimatedFile f;  // CUBICSPLINE needs three elements per key
        f.b.j["animations"][0]["samplers"][1]["interpolation"] = "CUBICSPLINE";
        expect_bad(f, {"samplers[1].output", "expected 6", "CUBICSPLINE"});
    }
    {
        AnimatedFile f;
        f.b.j["animations"][0]["samplers"][1]["interpolation"] = "BEZIER";
        expect_bad(f, {"animations[0].samplers[1].interpolation", "unknown interpolation 'BEZIER'"});
    }
    {
        AnimatedFile f;
        f.b.j["animations"][0]["channels"][0]["target"]["path"] = "colour";
        expect_bad(f, {"animations[0].channels[0].target.path", "unknown path 'colour'"});
    }
    {
        AnimatedFile f;
        f.b.j["animations"][0]["channels"][1]["target"]["node"] = 42;
        expect_bad(f, {"bad_anim.gltf", "animations[0].channels[1].target.node", "node 42 does not exist"});
    }
    {
        AnimatedFile f;
        f.b.j["animations"][0]["channels"][1]["sampler"] = 9;
        expect_bad(f, {"animations[0].channels[1].sampler", "sampler 9 does not exist"});
    }
    {
        AnimatedFile f;  // a rotation channel fed VEC3 values
        f.b.j["animations"][0]["channels"][0]["target"]["path"] = "rotation";
        expect_bad(f, {"output of animations[0].samplers[0]", "expected 4"});
    }
    {
        AnimatedFile f;
        f.b.j["nodes"][2]["matrix"] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        expect_bad(f, {"animations[0].channels[1].target.node", "matrix"});
    }
    {
        AnimatedFile f;  // a scale that reaches zero makes the moving mesh's transform singular
        f.add_channel(2, "scale", "LINEAR", f.b.floats({1, 1, 1, 0, 0, 0}, "VEC3"));
        Scene s = load_scene(f.b.write("zero.gltf"));
        test::expect_error_message([&] { pose_scene(s, 2.0); }, {"zero.gltf", "mesh 'mover'", "singular"});
    }
}

}  // namespace
}  // namespace npt::scene
