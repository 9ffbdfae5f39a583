#include "scene/obj_loader.h"

#include <spdlog/spdlog.h>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

#include "core/error.h"
#include "core/image_io.h"
#include "scene/mesh_utils.h"
#include "scene/obj_syntax.h"
#include "scene/texture_utils.h"

namespace npt::scene {
namespace fs = std::filesystem;

namespace {

std::string obj_message_line(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
    std::replace(s.begin(), s.end(), '\n', ';');
    return s;
}

Rgb rgb(const tinyobj::real_t* v) { return {float(v[0]), float(v[1]), float(v[2])}; }

int load_texture(const fs::path& dir, const std::string& texname, bool srgb, Scene& scene,
                 const std::string& where) {
    if (texname.empty()) return -1;
    const fs::path file = dir / texname;
    try {
        scene.textures.push_back(make_texture(read_image(file, srgb), file.string()));
    } catch (const Error& e) {
        throw Error(where + ": " + e.what());
    }
    return int(scene.textures.size()) - 1;
}

Material convert(const tinyobj::material_t& m, const fs::path& dir, Scene& scene, const std::string& file) {
    const std::string where = file + ": material '" + m.name + "'";
    Material out;
    out.name = m.name;
    out.base_color = rgb(m.diffuse);
    out.base_color_texture = load_texture(dir, m.diffuse_texname, true, scene, where + " map_Kd");
    out.metallic = 0.0f;
    out.emission = rgb(m.emission);
    out.emissive_texture = load_texture(dir, m.emissive_texname, true, scene, where + " map_Ke");
    // Ns is a Phong exponent; sqrt(2/(Ns+2)) is the Beckmann-matching roughness (Walter et al. 2007).
    out.roughness = std::sqrt(2.0f / (std::max(float(m.shininess), 0.0f) + 2.0f));
    out.specular = is_black(rgb(m.specular)) ? 0.0f : 1.0f;
    if (m.ior > 0.0f) out.ior = float(m.ior);
    // tinyobjloader folds Tr into dissolve (d = 1 - Tr).
    if (m.dissolve < 1.0f || m.illum == 4 || m.illum == 6 || m.illum == 7) out.transmission = 1.0f;
    if (!m.emissive_texname.empty() && is_black(out.emission)) out.emission = Rgb(1.0f);
    out.double_sided = true;  // OBJ has no notion of a back face
    out.is_volume = m.name == "volume";
    return out;
}

Material default_material() {
    Material m;
    m.name = "default";
    m.base_color = Rgb(1.0f);
    m.metallic = 0.0f;
    m.specular = 0.0f;
    m.double_sided = true;
    return m;
}

}  // namespace

void load_obj(const fs::path& path, Scene& scene, const Mat4& placement) {
    const std::string file = path.string();
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error(file + ": file not found");
    // Regular files only, read here: a FIFO or /dev/stdin named as the OBJ or its mtllib would block forever.
    if (!fs::is_regular_file(path, ec)) throw Error(file + ": not a regular file");
    const auto read_text = [](const fs::path& p) {
        std::ifstream f(p, std::ios::binary);
        if (!f) throw Error(p.string() + ": cannot open");
        std::stringstream ss;
        ss << f.rdbuf();
        return ss.str();
    };
    // Our strict pass first (obj_syntax.h): tinyobjloader turns what it cannot parse into 0. Then tinyobjloader
    // parses the texts we read (the MTL files concatenated), never opening a file itself.
    const std::string obj_text = read_text(path);
    std::string mtl_text;
    for (const std::string& lib : check_obj_text(obj_text, file)) {
        const fs::path mtl = path.parent_path() / lib;
        if (!fs::is_regular_file(mtl, ec)) {
            spdlog::warn("{}: material file '{}' not found (or not a regular file); its materials get the default",
                         file, mtl.string());
            continue;
        }
        const std::string text = read_text(mtl);
        check_mtl_text(text, mtl.string());
        scene.files.push_back(mtl);
        mtl_text += text + "\n";
    }
    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    tinyobj::ObjReader reader;
    if (!reader.ParseFromString(obj_text, mtl_text, config))
        throw Error(file + ": " + (reader.Error().empty() ? "cannot parse OBJ" : obj_message_line(reader.Error())));
    if (!reader.Warning().empty()) spdlog::warn("{}: {}", file, obj_message_line(reader.Warning()));

    const auto& attrib = reader.GetAttrib();
    const fs::path dir = path.parent_path();
    const int offset = int(scene.materials.size());
    for (const auto& m : reader.GetMaterials()) scene.materials.push_back(convert(m, dir, scene, file));
    int default_index = -1;
    auto material_index = [&](int id) {
        if (id >= 0 && size_t(id) < reader.GetMaterials().size()) return offset + id;
        if (default_index < 0) {
            default_index = int(scene.materials.size());
            scene.materials.push_back(default_material());
        }
        return default_index;
    };

    const size_t nv = attrib.vertices.size() / 3, nn = attrib.normals.size() / 3,
                 nt = attrib.texcoords.size() / 2;
    size_t faces = 0;
    for (const auto& shape : reader.GetShapes()) {
        const auto& sm = shape.mesh;
        // Group the shape's triangles by material; each group becomes one Mesh with its own vertex numbering.
        std::map<int, std::vector<size_t>> groups;
        for (size_t f = 0; f < sm.num_face_vertices.size(); ++f) {
            if (sm.num_face_vertices[f] != 3) continue;  // triangulation leaves lines/points aside
            groups[f < sm.material_ids.size() ? sm.material_ids[f] : -1].push_back(f);
        }
        for (const auto& [mat_id, face_list] : groups) {
            Mesh mesh;
            mesh.name = shape.name;
            mesh.material = material_index(mat_id);
            std::map<std::tuple<int, int, int>, uint32_t> remap;
            bool has_n = true, has_t = true;
            for (size_t f : face_list)
                for (size_t k = 0; k < 3; ++k) {
                    const auto& idx = sm.indices[f * 3 + k];
                    has_n = has_n && idx.normal_index >= 0;
                    has_t = has_t && idx.texcoord_index >= 0;
                }
            for (size_t f : face_list) {
                for (size_t k = 0; k < 3; ++k) {
                    const auto& idx = sm.indices[f * 3 + k];
                    const std::string where = file + ": shape '" + shape.name + "' face " + std::to_string(f);
                    if (idx.vertex_index < 0 || size_t(idx.vertex_index) >= nv)
                        throw Error(where + ": vertex index out of range");
                    if (has_n && size_t(idx.normal_index) >= nn)
                        throw Error(where + ": normal index out of range");
                    if (has_t && size_t(idx.texcoord_index) >= nt)
                        throw Error(where + ": texture coordinate index out of range");
                    auto key = std::make_tuple(idx.vertex_index, has_n ? idx.normal_index : -1,
                                               has_t ? idx.texcoord_index : -1);
                    auto [it, inserted] = remap.try_emplace(key, uint32_t(mesh.positions.size()));
                    if (inserted) {
                        const size_t v = size_t(idx.vertex_index);
                        mesh.positions.push_back({float(attrib.vertices[3 * v]),
                                                  float(attrib.vertices[3 * v + 1]),
                                                  float(attrib.vertices[3 * v + 2])});
                        if (has_n) {
                            const size_t n = size_t(idx.normal_index);
                            mesh.normals.push_back({float(attrib.normals[3 * n]),
                                                    float(attrib.normals[3 * n + 1]),
                                                    float(attrib.normals[3 * n + 2])});
                        }
                        if (has_t) {
                            const size_t t = size_t(idx.texcoord_index);
                            // OBJ's v runs bottom-up; glTF's (and our textures') top-down.
                            mesh.uvs.push_back(
                                {float(attrib.texcoords[2 * t]), 1.0f - float(attrib.texcoords[2 * t + 1])});
                        }
                    }
                    mesh.indices.push_back(it->second);
                }
            }
            faces += face_list.size();
            validate_mesh(mesh, file + ": shape '" + shape.name + "'");
            const Material& mat = scene.materials[size_t(mesh.material)];
            if (mat.is_volume) {
                VolumeInstance vol;
                vol.name = shape.name.empty() ? "volume" : shape.name;
                vol.local_to_world = placement;
                vol.declared_in = file;
                mesh_bounds(mesh, vol.local_min, vol.local_max);
                check_volume_placement(vol, file + ": volume '" + vol.name + "'");
                scene.volumes.push_back(std::move(vol));
                continue;
            }
            if (mat.normal_texture >= 0 && mesh.normals.empty()) generate_smooth_normals(mesh);
            transform_mesh(mesh, placement, file + ": shape '" + shape.name + "'");
            scene.meshes.push_back(std::move(mesh));
        }
    }
    if (faces == 0) throw Error(file + ": no triangles (is it an OBJ file?)");
}

}  // namespace npt::scene
