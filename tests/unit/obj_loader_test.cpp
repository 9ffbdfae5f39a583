// OBJ + MTL loader: geometry, grouping by material, the documented MTL mapping, uv flip, volume placeholders,
// and bad input (missing file, missing MTL -> default material with a warning, NaN, bad indices).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>

#include "core/error.h"
#include "scene/scene.h"
#include "test_support.h"

namespace npt::scene {
namespace {

namespace fs = std::filesystem;

void expect_obj_error(const fs::path& path, std::initializer_list<std::string> parts) {
    test::expect_error_message([&] { load_scene(path); }, parts);
}

const char* k_mtl = R"(newmtl red
Kd 0.8 0.1 0.1
Ks 0 0 0
Ns 98
newmtl glass
Kd 1 1 1
Ks 1 1 1
Ni 1.45
d 0.5
newmtl lamp
Kd 0 0 0
Ke 5 4 3
newmtl volume
Kd 1 1 1
)";

const char* k_obj = R"(mtllib room.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 1
o quad
usemtl red
f 1/1/1 2/2/1 3/3/1 4/4/1
usemtl glass
f 1 2 5
usemtl lamp
f 2 6 5
o box
usemtl volume
f 1 2 3
f 1 5 6
)";

TEST(ObjLoader, MeshesMaterialsAndMapping) {
    const fs::path dir = test::temp_dir();
    test::write_file(dir / "room.mtl", k_mtl);
    test::write_file(dir / "room.obj", k_obj);
    Scene s = load_scene(dir / "room.obj");
    ASSERT_EQ(s.meshes.size(), 3u);  // quad/red, quad/glass, quad/lamp; the volume shape is not a mesh
    const Mesh& quad = s.meshes[0];
    EXPECT_EQ(quad.name, "quad");
    EXPECT_EQ(quad.triangle_count(), 2u);  // the quad is triangulated
    ASSERT_EQ(quad.uvs.size(), quad.positions.size());
    ASSERT_EQ(quad.normals.size(), quad.positions.size());
    // vt 0 0 is the bottom-left in OBJ, the top-left row in glTF/our textures: v flips.
    EXPECT_FLOAT_EQ(quad.uvs[0].y, 1.0f);
    EXPECT_FLOAT_EQ(quad.uvs[2].y, 0.0f);

    const Material& red = s.materials[size_t(quad.material)];
    EXPECT_EQ(red.name, "red");
    EXPECT_FLOAT_EQ(red.base_color.x, 0.8f);
    EXPECT_EQ(red.metallic, 0.0f);
    EXPECT_EQ(red.specular, 0.0f);  // Ks black
    EXPECT_NEAR(red.roughness, std::sqrt(2.0f / 100.0f), 1e-6f);

    const Material& glass = s.materials[size_t(s.meshes[1].material)];
    EXPECT_EQ(glass.name, "glass");
    EXPECT_EQ(glass.specular, 1.0f);
    EXPECT_FLOAT_EQ(glass.ior, 1.45f);
    EXPECT_EQ(glass.transmission, 1.0f);
    EXPECT_TRUE(s.meshes[1].normals.empty());  // faces without vn stay flat

    const Material& lamp = s.materials[size_t(s.meshes[2].material)];
    EXPECT_FLOAT_EQ(lamp.emission.x, 5.0f);
    EXPECT_FLOAT_EQ(lamp.emission.z, 3.0f);

    ASSERT_EQ(s.volumes.size(), 1u);
    EXPECT_EQ(s.volumes[0].name, "box");
    EXPECT_FLOAT_EQ(s.volumes[0].local_max.z, 1.0f);
    EXPECT_FLOAT_EQ(s.volumes[0].local_min.x, 0.0f);
}

TEST(ObjLoader, MissingMtlGivesDefaultMaterial) {
    const fs::path dir = test::temp_dir();
    test::write_file(dir / "m.obj", "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
    Scene s = load_scene(dir / "m.obj");  // a warning, not an error
    ASSERT_EQ(s.meshes.size(), 1u);
    const Material& m = s.materials[size_t(s.meshes[0].material)];
    EXPECT_EQ(m.name, "default");
    EXPECT_FLOAT_EQ(m.base_color.y, 1.0f);
    EXPECT_EQ(m.specular, 0.0f);
    EXPECT_EQ(m.metallic, 0.0f);
}

TEST(ObjLoaderBadInput, MissingEmptyAndBroken) {
    const fs::path dir = test::temp_dir();
    expect_obj_error(dir / "none.obj", {"none.obj", "not found"});
    test::write_file(dir / "empty.obj", "");
    expect_obj_error(dir / "empty.obj", {"empty.obj", "no triangles"});
    // tinyobjloader reads the text "nan" as 0; an overflowing literal is how a non-finite value gets through.
    test::write_file(dir / "nan.obj", "v 0 0 0\nv 1e400 0 0\nv 0 1 0\nf 1 2 3\n");
    expect_obj_error(dir / "nan.obj", {"nan.obj"});
    test::write_file(dir / "tex.obj", "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl t\nf 1 2 3\n");
    test::write_file(dir / "t.mtl", "newmtl t\nmap_Kd missing.png\n");
    expect_obj_error(dir / "tex.obj", {"tex.obj", "material 't'", "map_Kd", "missing.png"});
}

// tinyobjloader turns numbers it cannot parse into 0 and reads indices with atoi, unchecked; our strict pass
// (scene/obj_syntax.h) reports each with its line.
TEST(ObjLoaderBadInput, NonFiniteNumbersAndBadIndices) {
    const fs::path dir = test::temp_dir();
    const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    const struct {
        const char* name;
        std::string text;
        std::vector<std::string> parts;
    } cases[] = {
        {"nan", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", {"line 2", "v:", "'nan' is not a finite number"}},
        {"inf", "v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n", {"line 2", "'inf'"}},
        {"overflow", "v 0 0 0\nv 1e400 0 0\nv 0 1 0\nf 1 2 3\n", {"line 2", "'1e400'"}},
        {"comma", "v 0 0 0\nv 1,5 0 0\nv 0 1 0\nf 1 2 3\n", {"line 2", "'1,5'"}},
        {"short", "v 0 0\n", {"line 1", "expected 3 to 7 numbers, got 2"}},
        {"vn", tri + "vn 0 0 nan\nf 1//1 2//1 3//1\n", {"line 4", "vn:"}},
        {"uv_range",
         tri + "vt 0 0\nf 1/1 2/1 3/9\n",
         {"line 5", "f:", "index 9 is out of range", "1 texture coordinates"}},
        {"uv_relative", tri + "vt 0 0\nf 1/-1 2/-1 3/-2\n", {"line 5", "relative index -2"}},
        {"normal_range", tri + "f 1//1 2//1 3//1\n", {"line 4", "0 normals"}},
        {"vertex_range", tri + "f 1 2 4\n", {"line 4", "index 4 is out of range (the file has 3 vertices)"}},
        {"zero", tri + "f 0 1 2\n", {"line 4", "index 0"}},
        {"beyond64", tri + "f 1 2 99999999999999999999999\n", {"line 4", "beyond 64 bits"}},
        {"beyond32", tri + "f 1 2 4294967299\n", {"line 4", "beyond 32 bits"}},
        {"notint", tri + "f 1 2 3.5\n", {"line 4", "'3.5' is not an integer index"}},
        {"parts", tri + "f 1/1/1/1 2 3\n", {"line 4", "more than three parts"}},
        {"mtl", "mtllib bad.mtl\n" + tri + "usemtl x\nf 1 2 3\n", {"bad.mtl", "line 2", "Kd:", "'nan'"}},
    };
    test::write_file(dir / "bad.mtl", "newmtl x\nKd 1 nan 0\n");
    for (const auto& c : cases) {
        const fs::path path = dir / (std::string(c.name) + ".obj");
        test::write_file(path, c.text);
        try {
            load_scene(path);
            ADD_FAILURE() << "no error for " << c.name;
        } catch (const Error& e) {
            for (const auto& part : c.parts)
                EXPECT_NE(std::string(e.what()).find(part), std::string::npos)
                    << e.what() << " lacks " << part;
        }
    }
    // Valid forms still load: relative indices, v/vt/vn, a w coordinate, vertex colours, comments.
    test::write_file(dir / "ok.obj",
                     "v 0 0 0 1\nv 1 0 0 0.5 0.5 0.5\nv +0 1 0 # top\nvt 0 0\nvn 0 0 1\n"
                     "f -3/1/1 -2/1/1 -1/1/1\n");
    const Scene s = load_scene(dir / "ok.obj");
    EXPECT_EQ(s.triangle_count(), 1u);
}

// A FIFO (or /dev/stdin) named as an MTL file or a texture would block the loader forever: regular files only.
TEST(ObjLoaderBadInput, FifosAreRefusedNotWaitedFor) {
    const fs::path dir = test::temp_dir();
    ASSERT_EQ(::mkfifo((dir / "pipe.mtl").c_str(), 0600), 0);
    ASSERT_EQ(::mkfifo((dir / "pipe.png").c_str(), 0600), 0);
    test::write_file(dir / "a.obj", "mtllib pipe.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl x\nf 1 2 3\n");
    EXPECT_EQ(load_scene(dir / "a.obj").triangle_count(), 1u);  // a warning, the default material
    test::write_file(dir / "t.mtl", "newmtl t\nmap_Kd pipe.png\n");
    test::write_file(dir / "b.obj", "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl t\nf 1 2 3\n");
    expect_obj_error(dir / "b.obj", {"b.obj", "map_Kd", "pipe.png", "not a regular file"});
    ASSERT_EQ(::mkfifo((dir / "c.obj").c_str(), 0600), 0);
    expect_obj_error(dir / "c.obj", {"c.obj", "not a regular file"});
}

}  // namespace
}  // namespace npt::scene
