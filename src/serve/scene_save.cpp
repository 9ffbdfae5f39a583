#include "serve/scene_save.h"

#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/json_file.h"
#include "core/temp_file.h"
#include "serve/scene_edits.h"

namespace npt::serve {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// "#<index>", the loader's label of an unnamed node (appended: GCC 12 -O3 warns falsely on "#" + std::to_string).
std::string node_label(size_t index) {
    std::string s = "#";
    s += std::to_string(index);
    return s;
}

std::string lower_ext(const fs::path& p) {
    std::string e = p.extension().string();
    for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
    return e;
}

std::string base64(const std::string& in) {
    static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    size_t i = 0;
    for (; i + 2 < in.size(); i += 3) {
        const uint32_t v = uint32_t(uint8_t(in[i])) << 16 | uint32_t(uint8_t(in[i + 1])) << 8 | uint8_t(in[i + 2]);
        for (int s = 18; s >= 0; s -= 6) out += k[(v >> s) & 63];
    }
    const size_t rest = in.size() - i;
    if (rest > 0) {
        uint32_t v = uint32_t(uint8_t(in[i])) << 16;
        if (rest == 2) v |= uint32_t(uint8_t(in[i + 1])) << 8;
        out += k[(v >> 18) & 63];
        out += k[(v >> 12) & 63];
        out += rest == 2 ? k[(v >> 6) & 63] : '=';
        out += '=';
    }
    return out;
}

// A glTF node's local matrix (its `matrix`, else T R S), as the loader computes it.
Mat4 node_local(const json& n) {
    if (n.contains("matrix") && n["matrix"].is_array() && n["matrix"].size() == 16) {
        double v[16];
        for (int i = 0; i < 16; ++i) v[i] = n["matrix"][size_t(i)].get<double>();
        return Mat4::from_column_major(v);
    }
    Trs t;
    if (n.contains("translation")) t.translation = n["translation"].get<V3>();
    if (n.contains("rotation")) {
        V4 q = n["rotation"].get<V4>();
        const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (len > 0) for (double& c : q) c /= len;
        t.rotation = q;
    }
    if (n.contains("scale")) t.scale = n["scale"].get<V3>();
    return t.matrix();
}

// The world matrix of node `index`'s parent (identity for a root), walking `children` lists.
Mat4 parent_world(const json& nodes, size_t index, int depth = 0) {
    if (depth > 1000) throw Error("node hierarchy too deep");
    for (size_t p = 0; p < nodes.size(); ++p) {
        const json& n = nodes[p];
        if (!n.contains("children")) continue;
        for (const json& c : n["children"])
            if (c.is_number_integer() && c.get<size_t>() == index) return parent_world(nodes, p, depth + 1) * node_local(n);
    }
    return Mat4::identity();
}

bool is_identity(const Mat4& m) {
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            if (std::abs(m.m[r][c] - (r == c ? 1.0 : 0.0)) > 1e-12) return false;
    return true;
}

// The node of a glTF document that is volume `v`: its name (or "#index" for an unnamed node), with a mesh whose
// primitives use the material named "volume". -1 when none; -2 when several have the name.
int find_volume_node(const json& doc, const scene::VolumeInstance& v) {
    int found = -1;
    const json& nodes = doc.value("nodes", json::array());
    for (size_t i = 0; i < nodes.size(); ++i) {
        const json& n = nodes[i];
        const std::string label = n.contains("name") && n["name"].is_string() && !n["name"].get<std::string>().empty()
                                      ? n["name"].get<std::string>()
                                      : node_label(i);
        if (label != v.name || !n.contains("mesh")) continue;
        found = found == -1 ? int(i) : -2;
    }
    return found;
}

V4 camera_quaternion(const scene::Camera& c) {
    Mat4 m;
    const Vec3 cols[3] = {c.right, c.up, -c.forward};
    for (int col = 0; col < 3; ++col)
        for (int r = 0; r < 3; ++r) m.m[r][col] = cols[col][r];
    return decompose(m).rotation;
}

}  // namespace

SceneSaver::SceneSaver(const fs::path& scene_file) : m_file(scene_file) {
    const std::string ext = lower_ext(scene_file);
    if (ext == ".json") {
        m_json = true;
    } else if (ext == ".gltf") {
        m_json = false;
    } else {
        m_why_not = scene_file.filename().string() + ": the viewer saves JSON scenes and .gltf files only (" + ext +
                    " is not written back); include it in a JSON scene (docs/formats.md) to place and save edits";
        return;
    }
    std::ifstream in(scene_file, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    m_text = ss.str();
    m_doc = parse_json_text(m_text, scene_file.string(), m_json);
    if (!m_doc.is_object()) m_why_not = scene_file.string() + ": not a JSON object";
}

json SceneSaver::apply(const scene::Scene& scene, const SceneEditsToSave& edits, std::vector<std::string>* notes) const {
    if (!can_save()) throw Error(m_why_not);
    json doc = m_doc;
    const auto note = [&](const std::string& s) {
        if (notes) notes->push_back(s);
    };
    const fs::path canonical_file = fs::weakly_canonical(m_file);
    for (size_t vi : edits.volumes) {
        if (vi >= scene.volumes.size()) continue;
        const scene::VolumeInstance& v = scene.volumes[vi];
        if (fs::weakly_canonical(v.declared_in) != canonical_file) {
            note("volume '" + v.name + "' is declared in " + v.declared_in.filename().string() +
                 ", not in the scene file: its edits are not saved (declare it in the JSON scene's \"volumes\")");
            continue;
        }
        const Trs t = decompose(v.local_to_world);
        json fill = volume_extras(v);
        if (m_json) {
            json& vols = doc["volumes"];
            bool done = false;
            for (size_t k = 0; vols.is_array() && k < vols.size() && !done; ++k) {
                json& e = vols[k];
                const std::string name = e.contains("name") && e["name"].is_string() ? e["name"].get<std::string>()
                                                                                     : "volumes[" + std::to_string(k) + "]";
                if (name != v.name) continue;
                e["translation"] = t.translation;
                e["rotation"] = t.rotation;
                e["scale"] = t.scale;
                for (const char* key : {"density_scale", "emission_scale", "shading", "crop"}) {
                    if (fill.contains(key))
                        e[key] = fill[key];
                    else
                        e.erase(key);
                }
                done = true;
            }
            if (!done) note("volume '" + v.name + "' not found in the JSON scene's \"volumes\": not saved");
        } else {
            const int ni = find_volume_node(doc, v);
            if (ni < 0) {
                note("volume '" + v.name + (ni == -2 ? "': several nodes have this name" : "': no node of that name") +
                     ": not saved");
                continue;
            }
            json& n = doc["nodes"][size_t(ni)];
            const Mat4 parent = parent_world(doc["nodes"], size_t(ni));
            n.erase("matrix");
            n.erase("translation");
            n.erase("rotation");
            n.erase("scale");
            if (is_identity(parent)) {
                n["translation"] = t.translation;
                n["rotation"] = t.rotation;
                n["scale"] = t.scale;
            } else {
                const Mat4 local = parent.inverse() * v.local_to_world;
                json m = json::array();
                for (int c = 0; c < 4; ++c)
                    for (int r = 0; r < 4; ++r) m.push_back(local.m[r][c]);
                n["matrix"] = m;
            }
            json& extras = n["extras"];
            if (!extras.is_object()) extras = json::object();
            json& vol = extras["volume"];
            if (!vol.is_object()) vol = json::object();
            for (const char* key : {"density_scale", "emission_scale", "shading", "crop"}) {
                if (fill.contains(key))
                    vol[key] = fill[key];
                else
                    vol.erase(key);
            }
        }
    }
    for (const auto& [li, factor] : edits.light_scales) {
        if (li >= scene.lights.size() || factor == 1.0) continue;
        const std::string& name = scene.lights[li].name;
        if (m_json) {
            note("light '" + name + "' comes from an included file: its intensity is not saved");
            continue;
        }
        json* lights = nullptr;
        if (doc.contains("extensions") && doc["extensions"].contains("KHR_lights_punctual"))
            lights = &doc["extensions"]["KHR_lights_punctual"]["lights"];
        bool done = false;
        for (size_t k = 0; lights && lights->is_array() && k < lights->size() && !done; ++k) {
            json& l = (*lights)[k];
            const bool named = l.contains("name") && l["name"].is_string() && l["name"].get<std::string>() == name;
            // An unnamed light takes its node's label: find the node that uses light k.
            bool by_node = false;
            if (!named && doc.contains("nodes"))
                for (size_t ni = 0; ni < doc["nodes"].size() && !by_node; ++ni) {
                    const json& n = doc["nodes"][ni];
                    const std::string label = n.value("name", std::string()).empty() ? node_label(ni)
                                                                                     : n["name"].get<std::string>();
                    by_node = label == name && n.contains("extensions") &&
                              n["extensions"].contains("KHR_lights_punctual") &&
                              n["extensions"]["KHR_lights_punctual"].value("light", -1) == int(k);
                }
            if (!named && !by_node) continue;
            l["intensity"] = l.value("intensity", 1.0) * factor;
            done = true;
        }
        if (!done) note("light '" + name + "' not found in " + m_file.filename().string() + ": not saved");
    }
    if (edits.spp || edits.max_depth) {
        json* settings = nullptr;
        if (m_json) {
            settings = &doc["render"];
        } else {
            const size_t si = doc.value("scene", 0);
            if (doc.contains("scenes") && doc["scenes"].is_array() && si < doc["scenes"].size())
                settings = &doc["scenes"][si]["extras"];
            else
                note("render settings: the glTF file has no scene to hold them: not saved");
        }
        if (settings) {
            if (!settings->is_object()) *settings = json::object();
            if (edits.spp) (*settings)["spp"] = *edits.spp;
            if (edits.max_depth) (*settings)["max_depth"] = *edits.max_depth;
        }
    }
    return doc;
}

std::vector<std::string> SceneSaver::save(const scene::Scene& scene, const SceneEditsToSave& edits) {
    std::vector<std::string> notes;
    const json doc = apply(scene, edits, &notes);
    if (!m_backed_up) {
        fs::path bak = m_file;
        bak += ".bak";
        write_text_atomic(bak, m_text);
        m_backed_up = true;
    }
    write_text_atomic(m_file, doc.dump(2) + "\n");
    return notes;
}

int SceneSaver::write_camera_path(const fs::path& path, const std::vector<scene::Camera>& keys, double seconds_per_key,
                                  double fps, int width, int height) {
    if (keys.size() < 2) throw Error("camera path: needs at least 2 keyframes (has " + std::to_string(keys.size()) + ")");
    std::vector<float> times, translations, rotations;
    for (size_t i = 0; i < keys.size(); ++i) {
        times.push_back(float(double(i) * seconds_per_key));
        for (int k = 0; k < 3; ++k) translations.push_back(keys[i].position[k]);
        V4 q = camera_quaternion(keys[i]);
        // Along the shorter arc from the previous key (glTF slerps as given).
        if (i > 0) {
            const size_t p = rotations.size() - 4;
            const double dot = q[0] * rotations[p] + q[1] * rotations[p + 1] + q[2] * rotations[p + 2] + q[3] * rotations[p + 3];
            if (dot < 0)
                for (double& c : q) c = -c;
        }
        for (double c : q) rotations.push_back(float(c));
    }
    std::string bin;
    const auto append = [&](const std::vector<float>& v) {
        const size_t offset = bin.size();
        bin.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(float));
        return offset;
    };
    const size_t o_t = append(times), o_tr = append(translations), o_r = append(rotations);
    const size_t n = keys.size();
    json views = json::array({{{"buffer", 0}, {"byteOffset", o_t}, {"byteLength", n * 4}},
                              {{"buffer", 0}, {"byteOffset", o_tr}, {"byteLength", n * 12}},
                              {{"buffer", 0}, {"byteOffset", o_r}, {"byteLength", n * 16}}});
    json accessors = json::array(
        {{{"bufferView", 0}, {"componentType", 5126}, {"count", n}, {"type", "SCALAR"},
          {"min", {times.front()}}, {"max", {times.back()}}},
         {{"bufferView", 1}, {"componentType", 5126}, {"count", n}, {"type", "VEC3"}},
         {{"bufferView", 2}, {"componentType", 5126}, {"count", n}, {"type", "VEC4"}}});
    const scene::Camera& k0 = keys.front();
    json doc = {
        {"asset", {{"version", "2.0"}, {"generator", "nerfpt serve"}}},
        {"scene", 0},
        {"scenes", {{{"nodes", {0}}}}},
        {"nodes", {{{"name", "viewer_path"}, {"camera", 0},
                    {"translation", {k0.position.x, k0.position.y, k0.position.z}},
                    {"rotation", camera_quaternion(k0)}}}},
        {"cameras", {{{"type", "perspective"},
                      {"perspective", {{"yfov", k0.yfov}, {"aspectRatio", double(width) / double(height)},
                                       {"znear", 0.01}}}}}},
        {"buffers", {{{"byteLength", bin.size()}, {"uri", "data:application/octet-stream;base64," + base64(bin)}}}},
        {"bufferViews", views},
        {"accessors", accessors},
        {"animations", {{{"name", "viewer_path"},
                         {"samplers", {{{"input", 0}, {"output", 1}, {"interpolation", "LINEAR"}},
                                       {{"input", 0}, {"output", 2}, {"interpolation", "LINEAR"}}}},
                         {"channels", {{{"sampler", 0}, {"target", {{"node", 0}, {"path", "translation"}}}},
                                       {{"sampler", 1}, {"target", {{"node", 0}, {"path", "rotation"}}}}}}}}}};
    write_text_atomic(path, doc.dump(2) + "\n");
    return int(std::floor(double(times.back()) * fps + 1e-9));
}

}  // namespace npt::serve
