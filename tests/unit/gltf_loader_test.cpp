// glTF loader: the shared reference scenes, small files written here for each feature, and bad input that
// must fail with one clear npt::Error naming the file and the field (never crash, hang or allocate absurd
// amounts).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <stb_image_write.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/image_io.h"
#include "gltf_builder.h"
#include "log_capture.h"
#include "scene/scene.h"
#include "test_support.h"

namespace npt::scene {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;
using test::base64;
using test::Builder;

std::string png_bytes(int w, int h, const std::vector<unsigned char>& rgb) {
    std::string out;
    stbi_write_png_to_func(
        [](void* ctx, void* data, int size) {
            static_cast<std::string*>(ctx)->append(static_cast<char*>(data), size_t(size));
        },
        &out, w, h, 3, rgb.data(), w * 3);
    return out;
}

// Expects load_scene to throw an npt::Error whose message contains each of `parts`.
void expect_gltf_error(const fs::path& path, std::initializer_list<std::string> parts,
                  const LoadOptions& opt = {}) {
    test::expect_error_message([&] { load_scene(path, opt); }, parts);
}

using test::expect_near;

const Mesh* find_mesh(const Scene& s, const std::string& name) {
    for (const auto& m : s.meshes)
        if (m.name == name) return &m;
    return nullptr;
}

TEST(GltfLoader, CornellReferenceScene) {
    const fs::path path = test::shared_data() / "scenes/cornell/scene.gltf";
    NPT_REQUIRE_SHARED(path);
    Scene s = load_scene(path);
    EXPECT_EQ(s.meshes.size(), 7u);
    EXPECT_EQ(s.triangle_count(), 6u * 2u + 3968u);
    const Mesh* lamp = find_mesh(s, "lamp");
    ASSERT_NE(lamp, nullptr);
    expect_near(s.materials[size_t(lamp->material)].emission, {20.0f, 17.0f, 12.0f}, 1e-4f);
    EXPECT_FALSE(s.materials[size_t(lamp->material)].double_sided);
    ASSERT_NE(find_mesh(s, "sphere"), nullptr);
    EXPECT_EQ(find_mesh(s, "sphere")->normals.size(), find_mesh(s, "sphere")->positions.size());
    for (const char* wall : {"floor", "back", "left", "right", "ceiling"}) {
        ASSERT_NE(find_mesh(s, wall), nullptr) << wall;
        EXPECT_TRUE(find_mesh(s, wall)->normals.empty()) << wall;
        EXPECT_EQ(s.materials[size_t(find_mesh(s, wall)->material)].specular, 0.0f);
    }
    ASSERT_EQ(s.camera, 0);
    const Camera& c = s.cameras[0];
    expect_near(c.position, {0.0f, 1.0f, 3.9f});
    expect_near(c.forward, {0.0f, 0.0f, -1.0f});
    expect_near(c.up, {0.0f, 1.0f, 0.0f});
    EXPECT_NEAR(c.yfov, 0.698132f, 1e-6f);
    EXPECT_NEAR(c.aspect, 1.33333f, 1e-4f);
    EXPECT_EQ(s.settings.width, 320);
    EXPECT_EQ(s.settings.height, 240);
    EXPECT_TRUE(s.environment.is_black());
    EXPECT_TRUE(s.volumes.empty());
}

TEST(GltfLoader, CornellVolumeReferenceScene) {
    const fs::path path = test::shared_data() / "scenes/cornell_volume/scene.gltf";
    NPT_REQUIRE_SHARED(path);
    Scene s = load_scene(path);
    ASSERT_EQ(s.volumes.size(), 1u);
    const VolumeInstance& v = s.volumes[0];
    EXPECT_EQ(v.name, "volume");
    expect_near(v.local_to_world.transform_point({0, 0, 0}), {-0.35f, 0.55f, -0.25f});
    expect_near(v.local_to_world.transform_point({1, 1, 1}), {0.15f, 1.05f, 0.25f});
    expect_near(v.local_min, {-1, -1, -1});
    expect_near(v.local_max, {1, 1, 1});
    const json extras = json::parse(v.extras_json);
    EXPECT_DOUBLE_EQ(extras["volume"]["density_scale"].get<double>(), 5.498);
    EXPECT_EQ(extras["volume"]["file"], "volume.vdb");
    EXPECT_EQ(s.meshes.size(), 8u);
    for (const auto& m : s.meshes) EXPECT_FALSE(s.materials[size_t(m.material)].is_volume) << m.name;
}

TEST(GltfLoader, NodeHierarchyComposesTransforms) {
    Builder b;
    int mesh = b.triangle();
    int child = b.node({{"name", "child"}, {"mesh", mesh}, {"translation", {0, 1, 0}}}, false);
    b.node({{"name", "parent"}, {"children", {child}}, {"translation", {1, 0, 0}}, {"scale", {2, 2, 2}}});
    Scene s = load_scene(b.write());
    ASSERT_EQ(s.meshes.size(), 1u);
    EXPECT_EQ(s.meshes[0].name, "child");
    // world = T(1,0,0) S(2) T(0,1,0): the origin goes to (1, 2, 0), (1,0,0) to (3, 2, 0).
    expect_near(s.meshes[0].positions[0], {1, 2, 0});
    expect_near(s.meshes[0].positions[1], {3, 2, 0});
}

TEST(GltfLoader, MatrixNodeIsColumnMajor) {
    Builder b;
    int mesh = b.triangle();
    // Column-major: translation in elements 12..14; a 90 degree rotation about z in the upper 3x3.
    b.node({{"mesh", mesh}, {"matrix", {0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 1, 0, 5, 6, 7, 1}}});
    Scene s = load_scene(b.write());
    ASSERT_EQ(s.meshes.size(), 1u);
    expect_near(s.meshes[0].positions[0], {5, 6, 7});
    expect_near(s.meshes[0].positions[1], {5, 7, 7});  // x axis -> y axis
}

TEST(GltfLoader, NegativeScaleReversesWinding) {
    Builder b;
    int p = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    int n = b.vec3({0, 0, 1, 0, 0, 1, 0, 0, 1});
    int mesh = b.mesh({{"POSITION", p}, {"NORMAL", n}}, b.indices32({0, 1, 2}));
    b.node({{"mesh", mesh}, {"scale", {-1, 1, 1}}});
    Scene s = load_scene(b.write());
    ASSERT_EQ(s.meshes.size(), 1u);
    const Mesh& m = s.meshes[0];
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 2, 1}));
    // The counter-clockwise (geometric) normal and the shading normal still agree: +z.
    Vec3 g = cross(m.positions[m.indices[1]] - m.positions[m.indices[0]],
                   m.positions[m.indices[2]] - m.positions[m.indices[0]]);
    EXPECT_GT(g.z, 0.0f);
    expect_near(m.normals[0], {0, 0, 1});
}

TEST(GltfLoader, NormalsUseInverseTranspose) {
    Builder b;
    // A 45 degree slanted normal under a non-uniform scale (2, 1, 1): the result is (1/2, 1, 0) normalised.
    const float r = 1.0f / std::sqrt(2.0f);
    int p = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    int n = b.vec3({r, r, 0, r, r, 0, r, r, 0});
    int mesh = b.mesh({{"POSITION", p}, {"NORMAL", n}}, b.indices32({0, 1, 2}));
    b.node({{"mesh", mesh}, {"scale", {2, 1, 1}}});
    Scene s = load_scene(b.write());
    expect_near(s.meshes[0].normals[0], normalize(Vec3(0.5f, 1.0f, 0.0f)));
}

TEST(GltfLoader, IndexTypesAndNonIndexed) {
    Builder b;
    int p = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0});
    int m16 = b.mesh({{"POSITION", p}}, b.indices16({0, 1, 2, 2, 1, 3}), -1, "u16");
    int m8 = b.mesh({{"POSITION", p}}, b.indices8({0, 1, 3}), -1, "u8");
    int m0 = b.mesh({{"POSITION", b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0})}}, -1, -1, "none");
    b.node({{"name", "a"}, {"mesh", m16}});
    b.node({{"name", "b"}, {"mesh", m8}});
    b.node({{"name", "c"}, {"mesh", m0}});
    Scene s = load_scene(b.write());
    ASSERT_EQ(s.meshes.size(), 3u);
    EXPECT_EQ(find_mesh(s, "a")->indices, (std::vector<uint32_t>{0, 1, 2, 2, 1, 3}));
    EXPECT_EQ(find_mesh(s, "b")->indices, (std::vector<uint32_t>{0, 1, 3}));
    EXPECT_EQ(find_mesh(s, "c")->indices, (std::vector<uint32_t>{0, 1, 2}));
    // No material: the glTF default (white, metallic 1, roughness 1).
    const Material& d = s.materials[size_t(s.meshes[0].material)];
    expect_near(d.base_color, {1, 1, 1});
    EXPECT_EQ(d.metallic, 1.0f);
    EXPECT_EQ(d.roughness, 1.0f);
    EXPECT_EQ(s.camera, -1);
}

TEST(GltfLoader, NonTrianglePrimitivesAreSkipped) {
    Builder b;
    int p = b.vec3({0, 0, 0, 1, 0, 0});
    b.j["meshes"].push_back({{"primitives", {{{"attributes", {{"POSITION", p}}}, {"mode", 1}}}}});
    b.node({{"mesh", 0}});
    int tri = b.triangle();
    b.node({{"mesh", tri}});
    Scene s = load_scene(b.write());
    EXPECT_EQ(s.meshes.size(), 1u);
}

Builder two_cameras() {
    Builder b;
    b.j["cameras"] = {
        {{"name", "wide"}, {"type", "perspective"}, {"perspective", {{"yfov", 1.0}, {"znear", 0.1}}}},
        {{"name", "tele"},
         {"type", "perspective"},
         {"perspective", {{"yfov", 0.2}, {"aspectRatio", 2.0}, {"znear", 0.1}}}}};
    b.node({{"name", "cam_a"}, {"camera", 0}, {"translation", {0, 0, 5}}});
    // Rotated 90 degrees about +y, scaled 3x: looks down -x; the scale must not leak into the frame.
    const float s = std::sqrt(0.5f);
    b.node({{"name", "cam_b"}, {"camera", 1}, {"rotation", {0, s, 0, s}}, {"scale", {3, 3, 3}}});
    return b;
}

TEST(GltfLoader, CameraSelection) {
    Builder b = two_cameras();
    const fs::path path = b.write();
    Scene first = load_scene(path);
    ASSERT_GE(first.camera, 0);
    EXPECT_EQ(first.cameras[size_t(first.camera)].name, "cam_a");
    expect_near(first.cameras[size_t(first.camera)].position, {0, 0, 5});
    EXPECT_EQ(first.cameras[size_t(first.camera)].aspect, 0.0f);

    for (const char* name : {"cam_b", "tele"}) {
        Scene s = load_scene(path, LoadOptions{name});
        const Camera& c = s.cameras[size_t(s.camera)];
        EXPECT_EQ(c.name, "cam_b");
        expect_near(c.forward, {-1, 0, 0});
        expect_near(c.right, {0, 0, -1});
        expect_near(c.up, {0, 1, 0});
        EXPECT_FLOAT_EQ(c.yfov, 0.2f);
        EXPECT_FLOAT_EQ(c.aspect, 2.0f);
    }
    expect_gltf_error(path, {"scene.gltf", "camera 'nope' not found", "cam_a", "cam_b"}, LoadOptions{"nope"});
}

TEST(GltfLoader, OrthographicCameraIsAnError) {
    Builder b;
    b.j["cameras"] = {{{"name", "ortho"},
                       {"type", "orthographic"},
                       {"orthographic", {{"xmag", 1}, {"ymag", 1}, {"znear", 0.1}, {"zfar", 10}}}}};
    b.node({{"name", "cam"}, {"camera", 0}});
    expect_gltf_error(b.write(), {"scene.gltf", "cam", "orthographic cameras are not supported yet"});
}

TEST(GltfLoader, PunctualLights) {
    Builder b;
    b.j["extensionsUsed"] = {"KHR_lights_punctual"};
    b.j["extensions"]["KHR_lights_punctual"]["lights"] = {
        {{"name", "bulb"}, {"type", "point"}, {"color", {1, 0.5, 0.25}}, {"intensity", 10}},
        {{"name", "spot"},
         {"type", "spot"},
         {"intensity", 2},
         {"spot", {{"innerConeAngle", 0.1}, {"outerConeAngle", 0.5}}}},
        {{"name", "sun"}, {"type", "directional"}, {"intensity", 3}}};
    b.node({{"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}, {"translation", {1, 2, 3}}});
    const float s = std::sqrt(0.5f);  // -90 degrees about x: local -z points down (-y)
    b.node({{"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}},
            {"rotation", {-s, 0, 0, s}},
            {"translation", {0, 4, 0}}});
    b.node({{"extensions", {{"KHR_lights_punctual", {{"light", 2}}}}}});
    Scene sc = load_scene(b.write());
    ASSERT_EQ(sc.lights.size(), 3u);
    EXPECT_EQ(sc.lights[0].type, PunctualType::Point);
    expect_near(sc.lights[0].position, {1, 2, 3});
    expect_near(sc.lights[0].intensity, {10, 5, 2.5f});
    EXPECT_EQ(sc.lights[1].type, PunctualType::Spot);
    expect_near(sc.lights[1].direction, {0, -1, 0});
    expect_near(sc.lights[1].position, {0, 4, 0});
    EXPECT_FLOAT_EQ(sc.lights[1].inner_cone, 0.1f);
    EXPECT_FLOAT_EQ(sc.lights[1].outer_cone, 0.5f);
    EXPECT_EQ(sc.lights[2].type, PunctualType::Directional);
    expect_near(sc.lights[2].direction, {0, 0, -1});
    expect_near(sc.lights[2].intensity, {3, 3, 3});
}

TEST(GltfLoader, MaterialExtensions) {
    Builder b;
    b.j["materials"] = {
        {{"name", "glass"},
         {"emissiveFactor", {1, 0.5, 0}},
         {"pbrMetallicRoughness",
          {{"baseColorFactor", {0.5, 0.25, 1, 1}}, {"metallicFactor", 0.2}, {"roughnessFactor", 0.3}}},
         {"extensions",
          {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4}}},
           {"KHR_materials_specular", {{"specularFactor", 0.7}, {"specularColorFactor", {1, 0, 0.5}}}},
           {"KHR_materials_transmission", {{"transmissionFactor", 0.9}}},
           {"KHR_materials_ior", {{"ior", 1.33}}}}}}};
    b.node({{"mesh", b.triangle(0)}});
    Scene s = load_scene(b.write());
    const Material& m = s.materials[size_t(s.meshes[0].material)];
    EXPECT_EQ(m.name, "glass");
    expect_near(m.base_color, {0.5f, 0.25f, 1});
    EXPECT_FLOAT_EQ(m.metallic, 0.2f);
    EXPECT_FLOAT_EQ(m.roughness, 0.3f);
    expect_near(m.emission, {4, 2, 0});
    EXPECT_FLOAT_EQ(m.specular, 0.7f);
    expect_near(m.specular_color, {1, 0, 0.5f});
    EXPECT_FLOAT_EQ(m.transmission, 0.9f);
    EXPECT_FLOAT_EQ(m.ior, 1.33f);
    EXPECT_FALSE(m.double_sided);
}

TEST(GltfLoader, TexturesEmbeddedExternalAndShared) {
    Builder b;
    // 2x1 PNG: texel values 188 and 64 (8-bit sRGB codes).
    const std::string png = png_bytes(2, 1, {188, 188, 188, 64, 64, 64});
    b.j["images"] = {{{"uri", "data:image/png;base64," + base64(png)}}, {{"uri", "tex.png"}}};
    b.j["textures"] = {{{"source", 0}}, {{"source", 1}}};
    b.j["materials"] = {
        {{"name", "a"},
         {"pbrMetallicRoughness",
          {{"baseColorTexture", {{"index", 0}}}, {"metallicRoughnessTexture", {{"index", 0}}}}},
         {"emissiveTexture", {{"index", 0}}},
         {"normalTexture", {{"index", 1}, {"scale", 0.5}}}}};
    int p = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    int uv = b.vec2({0, 0, 1, 0, 0, 1});
    b.node({{"mesh", b.mesh({{"POSITION", p}, {"TEXCOORD_0", uv}}, b.indices32({0, 1, 2}), 0)}});
    const fs::path path = b.write();
    test::write_file(path.parent_path() / "tex.png", png);
    Scene s = load_scene(path);
    const Material& m = s.materials[size_t(s.meshes[0].material)];
    // The same image as sRGB colour (base, emissive: one texture) and as linear data (metallic-roughness).
    EXPECT_EQ(m.base_color_texture, m.emissive_texture);
    EXPECT_NE(m.base_color_texture, m.metallic_roughness_texture);
    EXPECT_EQ(s.textures.size(), 3u);
    const Texture& srgb = s.textures[size_t(m.base_color_texture)];
    const Texture& lin = s.textures[size_t(m.metallic_roughness_texture)];
    ASSERT_EQ(srgb.width, 2);
    EXPECT_NEAR(srgb.rgba[0], srgb_to_linear(188 / 255.0f), 1e-6f);
    EXPECT_NEAR(srgb.rgba[4], srgb_to_linear(64 / 255.0f), 1e-6f);
    EXPECT_FLOAT_EQ(srgb.rgba[3], 1.0f);
    EXPECT_NEAR(lin.rgba[0], 188 / 255.0f, 1e-6f);
    EXPECT_FLOAT_EQ(m.normal_scale, 0.5f);
    // A normal texture on a mesh without normals: smooth normals are generated (+z for this triangle).
    ASSERT_EQ(s.meshes[0].normals.size(), 3u);
    expect_near(s.meshes[0].normals[0], {0, 0, 1});
    EXPECT_EQ(s.meshes[0].uvs.size(), 3u);

    fs::remove(path.parent_path() / "tex.png");
    expect_gltf_error(path, {"scene.gltf", "material 'a'", "image 1", "tex.png"});
}

TEST(GltfLoader, BinaryGlb) {
    Builder b;
    const std::string png = png_bytes(1, 1, {255, 0, 0});
    const int img_view = b.view(png.data(), png.size());
    b.j["images"] = {{{"bufferView", img_view}, {"mimeType", "image/png"}}};
    b.j["textures"] = {{{"source", 0}}};
    b.j["materials"] = {{{"name", "red"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}};
    b.node({{"name", "t"}, {"mesh", b.triangle(0)}, {"translation", {0, 0, -2}}});
    const fs::path path = test::temp_dir() / "scene.glb";
    test::write_file(path, b.glb());
    Scene s = load_scene(path);
    ASSERT_EQ(s.meshes.size(), 1u);
    expect_near(s.meshes[0].positions[1], {1, 0, -2});
    const Texture& t = s.textures[size_t(s.materials[size_t(s.meshes[0].material)].base_color_texture)];
    EXPECT_FLOAT_EQ(t.rgba[0], 1.0f);
    EXPECT_FLOAT_EQ(t.rgba[1], 0.0f);
}

TEST(GltfLoader, SceneExtrasSetRenderSettings) {
    Builder b;
    b.j["scenes"][0]["extras"] = {
        {"width", 64}, {"height", 32}, {"spp", 8}, {"max_depth", 3}, {"background", {0.1, 0.2, 0.3}}};
    b.node({{"mesh", b.triangle()}});
    Scene s = load_scene(b.write());
    EXPECT_EQ(s.settings.width, 64);
    EXPECT_EQ(s.settings.height, 32);
    EXPECT_EQ(s.settings.spp, 8);
    EXPECT_EQ(s.settings.max_depth, 3);
    expect_near(s.environment.color, {0.1f, 0.2f, 0.3f});
    b.j["scenes"][0]["extras"]["width"] = "wide";
    expect_gltf_error(b.write(), {"scene.gltf", "extras.width"});
}

// ---- bad input -------------------------------------------------------------------------------------------

TEST(GltfLoaderBadInput, MissingEmptyMalformed) {
    const fs::path dir = test::temp_dir();
    expect_gltf_error(dir / "absent.gltf", {"absent.gltf", "not found"});
    test::write_file(dir / "empty.gltf", "");
    expect_gltf_error(dir / "empty.gltf", {"empty.gltf", "empty"});
    test::write_file(dir / "bad.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [");
    expect_gltf_error(dir / "bad.gltf", {"bad.gltf"});
    test::write_file(dir / "bad.glb", "glTF\x02\0\0\0\xff\xff\xff\x7f");
    expect_gltf_error(dir / "bad.glb", {"bad.glb"});
}

TEST(GltfLoaderBadInput, BufferShorterThanAccessor) {
    Builder b;
    int mesh = b.triangle(-1, "floor");
    b.j["accessors"][0]["count"] = 100;  // 1200 bytes claimed, the view holds 36
    b.node({{"mesh", mesh}});
    expect_gltf_error(b.write(), {"scene.gltf", "accessor 0", "POSITION of mesh 'floor'", "1200 bytes",
                             "buffer view 0", "36"});
}

TEST(GltfLoaderBadInput, BufferViewBeyondBuffer) {
    Builder b;
    int mesh = b.triangle();
    b.j["bufferViews"][0]["byteOffset"] = 4096;
    b.node({{"mesh", mesh}});
    expect_gltf_error(b.write(), {"scene.gltf", "buffer view 0", "beyond buffer 0"});
}

TEST(GltfLoaderBadInput, IndexOutOfRange) {
    Builder b;
    int p = b.vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
    b.node({{"mesh", b.mesh({{"POSITION", p}}, b.indices32({0, 1, 7}), -1, "tri")}});
    expect_gltf_error(b.write(), {"scene.gltf", "mesh 'tri'", "index 2 = 7", "out of range"});
}

TEST(GltfLoaderBadInput, NanVertex) {
    Builder b;
    int p = b.vec3({0, 0, 0, std::nanf(""), 0, 0, 0, 1, 0});
    b.node({{"mesh", b.mesh({{"POSITION", p}}, b.indices32({0, 1, 2}), -1, "tri")}});
    expect_gltf_error(b.write(), {"scene.gltf", "mesh 'tri'", "accessor 0", "position 1", "not finite"});
}

TEST(GltfLoaderBadInput, AbsurdAccessorCount) {
    Builder b;
    int mesh = b.triangle();
    b.j["accessors"][0]["count"] = 1000000000000ULL;
    b.node({{"mesh", mesh}});
    expect_gltf_error(b.write(), {"scene.gltf", "accessor 0", "1000000000000"});
}

TEST(GltfLoaderBadInput, MissingBinFile) {
    Builder b;
    b.node({{"mesh", b.triangle()}});
    json d = b.j;
    d["buffers"] = {{{"byteLength", b.bin.size()}, {"uri", "missing.bin"}}};
    const fs::path path = test::temp_dir() / "scene.gltf";
    test::write_file(path, d.dump());
    expect_gltf_error(path, {"scene.gltf", "missing.bin"});
}

TEST(GltfLoaderBadInput, NodeCycle) {
    Builder b;
    b.node({{"children", {1}}});
    b.node({{"children", {0}}}, false);
    expect_gltf_error(b.write(), {"scene.gltf", "cycle"});
}

// tinygltf keeps the default where a value has the wrong type; check_schema reports it with its JSON path.
TEST(GltfLoaderBadInput, WrongTypesAreErrors) {
    struct Case {
        std::function<void(Builder&)> edit;
        std::vector<std::string> parts;
    };
    const std::vector<Case> cases = {
        {[](Builder& b) { b.j["meshes"][0]["primitives"] = 5; }, {"meshes[0].primitives", "got an integer"}},
        {[](Builder& b) {
             b.j["materials"] = json::array({{{"pbrMetallicRoughness", {{"baseColorFactor", "red"}}}}});
         },
         {"materials[0].pbrMetallicRoughness.baseColorFactor", "array of 4 numbers", "a string"}},
        {[](Builder& b) { b.j["scene"] = "zero"; }, {"scene", "index into 'scenes'", "a string"}},
        {[](Builder& b) { b.j["nodes"][0]["translation"] = "x"; }, {"nodes[0].translation", "array of 3"}},
        {[](Builder& b) { b.j["meshes"][0]["primitives"][0]["material"] = -1; },
         {"meshes[0].primitives[0].material", "integer >= 0", "-1"}},
        {[](Builder& b) { b.j["meshes"][0]["primitives"][0]["material"] = 3; },
         {"meshes[0].primitives[0].material", "3 does not exist", "'materials' has 0"}},
        {[](Builder& b) { b.j["nodes"][0]["mesh"] = 1.5; }, {"nodes[0].mesh", "1.5"}},
        {[](Builder& b) { b.j["accessors"][0]["type"] = "VEC9"; }, {"accessors[0].type", "'VEC9'"}},
        {[](Builder& b) { b.j["nodes"][0]["name"] = json::array(); }, {"nodes[0].name", "a string"}},
        {[](Builder& b) { b.j["meshes"][0]["primitives"] = json::array(); },
         {"meshes[0].primitives", "empty"}},
    };
    for (const Case& c : cases) {
        Builder b;
        b.node({{"name", "n"}, {"mesh", b.triangle()}});
        c.edit(b);
        std::vector<std::string> parts{"scene.gltf"};
        parts.insert(parts.end(), c.parts.begin(), c.parts.end());
        try {
            load_scene(b.write());
            ADD_FAILURE() << "no error for " << c.parts[0];
        } catch (const Error& e) {
            for (const auto& part : parts)
                EXPECT_NE(std::string(e.what()).find(part), std::string::npos)
                    << e.what() << " lacks " << part;
        }
    }
}

// Out of the spec's range: numbers with no sensible nearest value are errors (pbrt's rule), factors the spec
// bounds to [0, 1] are clamped with one warning per field (Blender's).
TEST(GltfLoaderBadInput, OutOfRangeValues) {
    const auto material = [](json ext, json pbr = json::object()) {
        Builder b;
        b.j["materials"] =
            json::array({{{"name", "mat"}, {"extensions", ext}, {"pbrMetallicRoughness", pbr}}});
        b.node({{"mesh", b.triangle(0)}});
        return b;
    };
    expect_gltf_error(material({{"KHR_materials_ior", {{"ior", -1}}}}).write(),
                 {"scene.gltf", "materials[0].extensions.KHR_materials_ior.ior", "-1", ">= 1"});
    expect_gltf_error(material({{"KHR_materials_emissive_strength", {{"emissiveStrength", -100}}}}).write(),
                 {"scene.gltf", "emissiveStrength", "-100", ">= 0"});
    {
        Builder b;
        b.j["cameras"] =
            json::array({{{"type", "perspective"},
                          {"perspective", {{"yfov", 0.5}, {"znear", 0.1}, {"aspectRatio", -2}}}}});
        b.node({{"camera", 0}});
        b.node({{"mesh", b.triangle()}});
        expect_gltf_error(b.write(), {"scene.gltf", "cameras[0].perspective.aspectRatio", "-2", "> 0"});
    }
    {
        Builder b;
        b.node({{"mesh", b.triangle()}, {"rotation", {0, 0, 0, 0}}});
        expect_gltf_error(b.write(), {"scene.gltf", "nodes[0].rotation", "zero"});
    }
    {
        Builder b;
        b.j["extensions"]["KHR_lights_punctual"]["lights"] =
            json::array({{{"type", "point"}, {"intensity", -5}}});
        b.node({{"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
        b.node({{"mesh", b.triangle()}});
        expect_gltf_error(b.write(), {"scene.gltf", "KHR_lights_punctual.lights[0].intensity", "-5"});
    }
    test::LogCapture log;
    Builder b = material({{"KHR_materials_transmission", {{"transmissionFactor", 5}}}},
                         {{"roughnessFactor", -3}, {"metallicFactor", 0.5}});
    b.j["materials"].push_back({{"name", "other"}, {"pbrMetallicRoughness", {{"roughnessFactor", 7}}}});
    b.node({{"mesh", b.triangle(1)}});
    const Scene s = load_scene(b.write());
    ASSERT_EQ(s.materials.size(), 2u);
    EXPECT_EQ(s.materials[0].transmission, 1.0f);
    EXPECT_EQ(s.materials[0].roughness, 0.0f);
    EXPECT_EQ(s.materials[0].metallic, 0.5f);
    EXPECT_EQ(s.materials[1].roughness, 1.0f);
    // roughnessFactor twice (two materials) and transmissionFactor once: one warning per field.
    EXPECT_EQ(log.warnings(), 2) << log.text();
    EXPECT_NE(log.text().find("roughnessFactor -3 is outside [0, 1], clamped to 0"), std::string::npos)
        << log.text();
}

// The finiteness check runs on world-space data: finite local positions and a finite matrix can still
// overflow a float (or leave the range Embree accepts) once multiplied.
TEST(GltfLoaderBadInput, TransformsOverflowingWorldSpace) {
    {
        Builder b;
        const int p = b.vec3({1, 0, 0, 2, 0, 0, 1, 1, 0});
        const int mesh = b.mesh({{"POSITION", p}}, b.indices32({0, 1, 2}), -1, "tri");
        // x' = 3e38 x + 3e38: finite in double, beyond a float.
        b.node({{"name", "big"},
                {"mesh", mesh},
                {"matrix", {3e38, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 3e38, 0, 0, 1}}});
        expect_gltf_error(b.write(), {"scene.gltf", "mesh 'tri'", "position 0", "not finite in world space"});
    }
    {
        Builder b;
        b.node({{"name", "far"}, {"mesh", b.triangle()}, {"scale", {1e30, 1e30, 1e30}}});
        expect_gltf_error(b.write(), {"scene.gltf", "position 1", "beyond", "in world space"});
    }
    {
        Builder b;
        b.j["cameras"] =
            json::array({{{"type", "perspective"}, {"perspective", {{"yfov", 0.5}, {"znear", 0.1}}}}});
        b.node({{"name", "cam"}, {"camera", 0}, {"translation", {1e30, 0, 0}}});
        b.node({{"mesh", b.triangle()}});
        expect_gltf_error(b.write(), {"scene.gltf", "camera 'cam'", "position", "beyond"});
    }
}

TEST(GltfLoaderBadInput, DeeplyNestedExtrasAreRefusedNotACrash) {
    Builder b;
    b.node({{"mesh", b.triangle()}});
    std::string text = b.gltf();
    const std::string deep = std::string(100000, '[') + std::string(100000, ']');
    text.insert(text.rfind('}'), ", \"extras\": " + deep);
    const fs::path path = test::temp_dir() / "deep.gltf";
    test::write_file(path, text);
    expect_gltf_error(path, {"deep.gltf", "nested deeper than 256 levels"});
}

// A buffer URI naming a FIFO (or /dev/stdin) would block tinygltf's reader forever: regular files only.
TEST(GltfLoaderBadInput, FifoBufferIsRefusedNotWaitedFor) {
    Builder b;
    b.node({{"mesh", b.triangle()}});
    json d = b.j;
    d["buffers"] = {{{"byteLength", b.bin.size()}, {"uri", "pipe.bin"}}};
    const fs::path path = test::temp_dir() / "scene.gltf";
    ASSERT_EQ(::mkfifo((path.parent_path() / "pipe.bin").c_str(), 0600), 0);
    test::write_file(path, d.dump());
    expect_gltf_error(path, {"scene.gltf", "pipe.bin"});
}

}  // namespace
}  // namespace npt::scene
