// JSON scene format: includes with placements, camera (explicit or by name), environment map, background and
// render settings; bad input names the file and the field.
#include "scene/json_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/image_io.h"
#include "scene/scene.h"
#include "test_support.h"

namespace npt::scene {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

void expect_scene_error(const fs::path& path, std::initializer_list<std::string> parts) {
    test::expect_error_message([&] { load_scene(path); }, parts);
}

using test::expect_near;

// A folder with a one-triangle OBJ and a glTF holding only a named camera.
fs::path make_assets() {
    const fs::path dir = test::temp_dir();
    test::write_file(dir / "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n");
    const json cam = {
        {"asset", {{"version", "2.0"}}},
        {"scene", 0},
        {"scenes", {{{"nodes", {0}}}}},
        {"nodes", {{{"name", "cam"}, {"camera", 0}, {"translation", {0, 0, 7}}}}},
        {"cameras", {{{"type", "perspective"}, {"perspective", {{"yfov", 0.5}, {"znear", 0.1}}}}}}};
    test::write_file(dir / "cam.gltf", cam.dump());
    return dir;
}

TEST(JsonScene, FullExample) {
    const fs::path dir = make_assets();
    Image sky(8, 4, 3);
    for (auto& v : sky.pixels) v = 0.5f;
    write_exr(dir / "sky.exr", sky);
    const float s = std::sqrt(0.5f);
    const json j = {
        {"include",
         {"tri.obj",
          {{"file", "tri.obj"},
           {"translation", {10, 0, 0}},
           {"rotation", {0, 0, s, s}},
           {"scale", {2, 2, 2}}},
          "cam.gltf"}},
        {"camera", {{"position", {0, 1, 4}}, {"look_at", {0, 1, 0}}, {"up", {0, 1, 0}}, {"yfov_deg", 40}}},
        {"environment", {{"file", "sky.exr"}, {"strength", 2.0}, {"rotation_deg", 90}}},
        {"background", {0.1, 0.2, 0.3}},
        {"render", {{"width", 100}, {"height", 50}, {"spp", 4}, {"max_depth", 5}, {"seed", 7}}}};
    test::write_file(dir / "scene.json", j.dump(2));
    Scene sc = load_scene(dir / "scene.json");
    ASSERT_EQ(sc.meshes.size(), 2u);
    expect_near(sc.meshes[0].positions[1], {1, 0, 0});
    // T(10,0,0) R(90 deg about z) S(2): (1,0,0) -> (10, 2, 0); the normal stays +z.
    expect_near(sc.meshes[1].positions[1], {10, 2, 0});
    expect_near(sc.meshes[1].normals[0], {0, 0, 1});
    ASSERT_GE(sc.camera, 0);
    const Camera& c = sc.cameras[size_t(sc.camera)];
    expect_near(c.position, {0, 1, 4});
    expect_near(c.forward, {0, 0, -1});
    expect_near(c.right, {1, 0, 0});
    expect_near(c.up, {0, 1, 0});
    EXPECT_NEAR(c.yfov, 40.0f * k_pi / 180.0f, 1e-6f);
    ASSERT_GE(sc.environment.texture, 0);
    EXPECT_FLOAT_EQ(sc.textures[size_t(sc.environment.texture)].rgba[0], 0.5f);
    EXPECT_FLOAT_EQ(sc.environment.strength, 2.0f);
    EXPECT_NEAR(sc.environment.rotation_y, k_pi / 2, 1e-6f);
    expect_near(sc.environment.color, {0.1f, 0.2f, 0.3f});
    EXPECT_EQ(sc.settings.width, 100);
    EXPECT_EQ(sc.settings.height, 50);
    EXPECT_EQ(sc.settings.spp, 4);
    EXPECT_EQ(sc.settings.max_depth, 5);
    EXPECT_EQ(sc.settings.seed, 7u);
}

TEST(JsonScene, VolumesArePlacedCubesWithTheirFill) {
    const fs::path dir = make_assets();
    const json j = {{"include", {"tri.obj"}},
                    {"volumes",
                     {{{"name", "cloud"},
                       {"file", "8x8x8_c.bin"},
                       {"translation", {1, 2, 3}},
                       {"scale", {0.5, 0.5, 0.5}},
                       {"density_scale", 2.5},
                       {"casts_shadows", false}}}}};
    test::write_file(dir / "vol.json", j.dump(2));
    Scene sc = load_scene(dir / "vol.json");
    ASSERT_EQ(sc.volumes.size(), 1u);
    const VolumeInstance& v = sc.volumes[0];
    EXPECT_EQ(v.name, "cloud");
    EXPECT_EQ(v.declared_in, dir / "vol.json");
    expect_near(v.local_to_world.transform_point({1, 1, 1}), {1.5f, 2.5f, 3.5f});
    const json extras = json::parse(v.extras_json);
    EXPECT_EQ(extras["volume"]["file"], "8x8x8_c.bin");
    EXPECT_EQ(extras["volume"]["density_scale"], 2.5);
    EXPECT_EQ(extras["volume"]["casts_shadows"], false);
    EXPECT_FALSE(extras["volume"].contains("translation"));

    test::write_file(dir / "bad.json", R"({"volumes": [{"translation": [0, 0, 0]}]})");
    expect_scene_error(dir / "bad.json", {"bad.json", "volumes[0].file"});
    test::write_file(dir / "bad2.json", R"({"volumes": {"file": "x"}})");
    expect_scene_error(dir / "bad2.json", {"bad2.json", "volumes"});
}

TEST(JsonScene, CameraByName) {
    const fs::path dir = make_assets();
    test::write_file(dir / "a.json", R"({"include": ["tri.obj", "cam.gltf"], "camera": {"name": "cam"}})");
    Scene s = load_scene(dir / "a.json");
    expect_near(s.cameras[size_t(s.camera)].position, {0, 0, 7});
    test::write_file(dir / "b.json", R"({"include": ["cam.gltf"], "camera": {"name": "other"}})");
    expect_scene_error(dir / "b.json", {"b.json", "camera.name", "'other' not found", "'cam'"});
}

TEST(JsonScene, UnknownKeysAreWarnings) {
    const fs::path dir = make_assets();
    test::write_file(dir / "w.json",
                     R"({"include": ["tri.obj"], "lights": [], "render": {"spp": 2, "fast": true}})");
    Scene s = load_scene(dir / "w.json");
    EXPECT_EQ(s.settings.spp, 2);
}

TEST(JsonSceneBadInput, WrongTypesAndMissingFiles) {
    const fs::path dir = make_assets();
    struct Case {
        std::string text;
        std::vector<std::string> parts;
    };
    const Case cases[] = {
        {"", {"empty"}},
        {"{\"include\": [", {"not valid JSON"}},
        {"[1, 2]", {"expected an object"}},
        {R"({"include": "tri.obj"})", {"include", "expected an array"}},
        {R"({"include": ["gone.obj"]})", {"include[0]", "gone.obj", "not found"}},
        {R"({"include": [{"file": "tri.obj", "scale": [1, 0, 1]}]})", {"include[0].scale"}},
        {R"({"include": [{"file": "tri.obj", "translation": "up"}]})",
         {"include[0].translation", "3 numbers"}},
        {R"({"camera": {"position": [0, 1, 4], "look_at": [0, 1]}})",
         {"camera.look_at: expected an array of 3 numbers"}},
        {R"({"camera": {"position": [0, 1, 4], "look_at": [0, 1, 4]}})", {"camera.look_at"}},
        {R"({"camera": {"position": [0, 1, 4], "look_at": [0, 1, 0], "yfov_deg": "wide"}})",
         {"camera.yfov_deg"}},
        {R"({"environment": {"file": "sky.exr"}})", {"environment.file", "sky.exr", "not found"}},
        {R"({"background": [0, 0]})", {"background"}},
        {R"({"render": {"width": -5}})", {"render.width"}},
        {R"({"render": {"spp": 1.5}})", {"render.spp"}},
        {R"({"background": [0, -1, 0]})", {"background", "must not be negative"}},
        {R"({"background": [0, 1e300, 0]})", {"background", "range of a float"}},
        {R"({"camera": {"position": [0, 1, 4], "look_at": [0, 1, 0], "aspect": -2}})", {"camera.aspect"}},
        {R"({"camera": {"position": [1e30, 1, 4], "look_at": [0, 1, 0]}})", {"camera", "position", "beyond"}},
        {R"({"include": [{"file": "tri.obj", "scale": [1e30, 1e30, 1e30]}]})",
         {"tri.obj", "beyond", "world space"}},
        {R"({"volumes": [{"file": "x.bin", "scale": [1e30, 1, 1]}]})",
         {"volumes[0]", "cube corner", "beyond"}},
        {R"({"a": )" + std::string(1000, '[') + "]}", {"nested deeper"}},
        {R"({"render": {"seed": 1e400}})", {"not valid JSON", "1e400", "line 1"}},
    };
    for (size_t i = 0; i < std::size(cases); ++i) {
        const fs::path p = dir / ("bad" + std::to_string(i) + ".json");
        test::write_file(p, cases[i].text);
        SCOPED_TRACE(cases[i].text);
        try {
            load_scene(p);
            ADD_FAILURE() << "no error for " << cases[i].text;
        } catch (const Error& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find(p.filename().string()), std::string::npos) << msg;
            EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
            for (const auto& part : cases[i].parts) EXPECT_NE(msg.find(part), std::string::npos) << msg;
        }
    }
}

TEST(SceneDispatch, UnknownExtension) {
    const fs::path dir = test::temp_dir();
    test::write_file(dir / "x.ply", "ply\n");
    expect_scene_error(dir / "x.ply", {"x.ply", "unknown scene format"});
}

}  // namespace
}  // namespace npt::scene
