// Saving the viewer's edits (serve/scene_save.h, serve/scene_edits.h): the saved file loads back with the volume
// where the viewer placed it and the fill it was given, for JSON scenes and glTF files.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/error.h"
#include "gltf_builder.h"
#include "scene/animation.h"
#include "serve/scene_edits.h"
#include "serve/scene_save.h"
#include "test_support.h"

namespace npt::serve {
namespace {
namespace fs = std::filesystem;

fs::path copy_serve_scene() {
    const fs::path dir = test::temp_dir();
    for (const auto& e : fs::directory_iterator(test::test_data() / "serve")) fs::copy_file(e.path(), dir / e.path().filename());
    return dir / "scene.json";
}

void expect_same_matrix(const Mat4& a, const Mat4& b, double tol = 1e-5) {
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(a.m[r][c], b.m[r][c], tol) << r << "," << c;
}

TEST(ServeSceneSave, DecomposeRoundTripsTranslationRotationScale) {
    Trs t;
    t.translation = {1, -2, 3};
    const double s = std::sqrt(0.5);
    t.rotation = {0, s, 0, s};
    t.scale = {0.5, 2, 3};
    const Trs back = decompose(t.matrix());
    expect_same_matrix(back.matrix(), t.matrix(), 1e-12);
    Trs mirror = t;
    mirror.scale = {-1, 1, 1};
    expect_same_matrix(decompose(mirror.matrix()).matrix(), mirror.matrix(), 1e-12);
}

TEST(ServeSceneSave, JsonSceneVolumeMovedAndFilledLoadsBackTheSame) {
    const fs::path file = copy_serve_scene();
    scene::Scene s = scene::load_scene(file);
    ASSERT_EQ(s.volumes.size(), 1u);
    Trs t = decompose(s.volumes[0].local_to_world);
    t.translation = {1, 0.25, 0};
    t.rotation = {0, 0, std::sin(0.3), std::cos(0.3)};
    place_volume(s.volumes[0], t);
    VolumeMsg fill;
    fill.emission_scale = 0.5;
    EXPECT_TRUE(edit_volume_fill(s.volumes[0], fill));
    EXPECT_FALSE(edit_volume_fill(s.volumes[0], fill));  // unchanged: no reload
    SceneSaver saver(file);
    ASSERT_TRUE(saver.can_save());
    SceneEditsToSave e;
    e.volumes = {0};
    e.spp = 9;
    EXPECT_TRUE(saver.save(s, e).empty());
    EXPECT_TRUE(fs::exists(file.string() + ".bak"));
    const scene::Scene back = scene::load_scene(file);
    expect_same_matrix(back.volumes[0].local_to_world, s.volumes[0].local_to_world);
    EXPECT_DOUBLE_EQ(volume_extras(back.volumes[0]).value("emission_scale", 0.0), 0.5);
    EXPECT_EQ(back.settings.spp, 9);
    EXPECT_EQ(back.meshes.size(), s.meshes.size());
    // Saving again from the same edits gives the same file (it is rewritten from the text as loaded).
    const std::string first = test::read_text(file);
    saver.save(s, e);
    EXPECT_EQ(test::read_text(file), first);
}

TEST(ServeSceneSave, GltfVolumeNodeUnderAParentGetsTheMatrixThatPutsItThere) {
    using test::Builder;
    Builder b;
    const int pos = b.vec3({-1, -1, -1, 1, -1, -1, 1, 1, -1, -1, 1, -1, -1, -1, 1, 1, -1, 1, 1, 1, 1, -1, 1, 1});
    const int idx = b.indices32({0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7});
    b.j["materials"] = {{{"name", "volume"}}};
    const int mesh = b.mesh({{"POSITION", pos}}, idx, 0);
    b.j["nodes"] = {{{"name", "parent"}, {"translation", {0, 1, 0}}, {"scale", {2, 2, 2}}, {"children", {1}}},
                    {{"name", "cloud"}, {"mesh", mesh}, {"extras", {{"volume", {{"file", "64x64x64_x.bin"}}}}}}};
    b.j["scenes"][0]["nodes"] = {0};
    const fs::path file = test::temp_dir() / "scene.gltf";
    b.j["buffers"] = {{{"byteLength", b.bin.size()}, {"uri", "data:application/octet-stream;base64," + test::base64(b.bin)}}};
    test::write_file(file, b.j.dump());
    scene::Scene s = scene::load_scene(file);
    ASSERT_EQ(s.volumes.size(), 1u);
    Trs t = decompose(s.volumes[0].local_to_world);
    t.translation = {3, 1, -1};
    place_volume(s.volumes[0], t);
    VolumeMsg fill;
    fill.density_scale = 4;
    fill.crop = std::make_pair(V3{0.1, 0.2, 0.3}, V3{0.9, 0.8, 0.7});
    edit_volume_fill(s.volumes[0], fill);
    SceneSaver saver(file);
    SceneEditsToSave e;
    e.volumes = {0};
    EXPECT_TRUE(saver.save(s, e).empty());
    const scene::Scene back = scene::load_scene(file);
    expect_same_matrix(back.volumes[0].local_to_world, s.volumes[0].local_to_world);
    const nlohmann::json extras = volume_extras(back.volumes[0]);
    EXPECT_EQ(extras["file"], "64x64x64_x.bin");
    EXPECT_DOUBLE_EQ(extras["density_scale"].get<double>(), 4.0);
    EXPECT_DOUBLE_EQ(extras["crop"]["max"][0].get<double>(), 0.9);
}

TEST(ServeSceneSave, RefusesFormatsItCannotWriteWithAReason) {
    SceneSaver glb("x/scene.glb");
    EXPECT_FALSE(glb.can_save());
    EXPECT_NE(glb.why_not().find("JSON scene"), std::string::npos) << glb.why_not();
}

TEST(ServeSceneSave, CameraPathIsAnAnimationTheLoaderPlays) {
    const fs::path dir = test::temp_dir();
    std::vector<scene::Camera> keys(3);
    for (int i = 0; i < 3; ++i) keys[size_t(i)].position = Vec3(float(i), 0, 5);
    const int frames = SceneSaver::write_camera_path(dir / "path.gltf", keys, 0.5, 24, 160, 120);
    EXPECT_EQ(frames, 24);
    scene::Scene s = scene::load_scene(dir / "path.gltf");
    ASSERT_TRUE(s.animation);
    scene::pose_scene(s, 0.5);
    test::expect_near(s.cameras[size_t(s.camera)].position, Vec3(1, 0, 5), 1e-4f);
    test::expect_error_message([&] { SceneSaver::write_camera_path(dir / "p.gltf", {keys[0]}, 1, 24, 1, 1); },
                               {"camera path", "2 keyframes"});
}

}  // namespace
}  // namespace npt::serve
