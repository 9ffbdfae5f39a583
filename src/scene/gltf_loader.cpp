// glTF 2.0 loading: parse with tinygltf (our own image callback keeps encoded bytes so that textures are
// decoded once, in the right colour space), then walk the scene's node tree and flatten it into world space.
#include "scene/gltf_loader.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "core/error.h"
#include "core/json_file.h"
#include "scene/animation.h"
#include "scene/gltf_internal.h"
#include "scene/mesh_utils.h"

namespace npt::scene {
namespace fs = std::filesystem;
using gltf::Context;

namespace {

// Keeps the encoded image; decoding happens in MaterialTable, which knows the colour space.
bool keep_encoded_image(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                        const unsigned char* bytes, int size, void*) {
    image->image.assign(bytes, bytes + size);
    return true;
}

// tinygltf reports several problems as newline-separated text; we print one line.
std::string one_line(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
    std::replace(s.begin(), s.end(), '\n', ';');
    return s;
}

// The document's JSON: the whole file, or a .glb's first chunk (12-byte header, then chunk length, type
// 'JSON', data), read after checking the lengths against the file size.
std::string json_text(const fs::path& path, bool binary) {
    const std::string file = path.string();
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(file + ": cannot open");
    if (!binary) {
        std::stringstream ss;
        ss << f.rdbuf();
        return ss.str();
    }
    std::error_code ec;
    const uintmax_t size = fs::file_size(path, ec);
    unsigned char header[20] = {};
    if (ec || size < 20 || !f.read(reinterpret_cast<char*>(header), 20))
        throw Error(file + ": truncated GLB header (" + std::to_string(size) + " bytes)");
    const auto u32 = [&](int at) {
        return uint32_t(header[at]) | uint32_t(header[at + 1]) << 8 | uint32_t(header[at + 2]) << 16 |
               uint32_t(header[at + 3]) << 24;
    };
    if (u32(4) != 2) throw Error(file + ": GLB version " + std::to_string(u32(4)) + " (expected 2)");
    if (u32(16) != 0x4E4F534Au) throw Error(file + ": GLB's first chunk is not JSON");
    const uint32_t length = u32(12);
    if (length == 0 || uint64_t(length) > size - 20)
        throw Error(file + ": GLB JSON chunk of " + std::to_string(length) +
                    " bytes does not fit the file (" + std::to_string(size) + " bytes)");
    std::string text(length, '\0');
    if (!f.read(text.data(), std::streamsize(length))) throw Error(file + ": cannot read the GLB JSON chunk");
    return text;
}

// Buffers and images a glTF names by URI are read only from regular files: a URI naming /dev/stdin or a FIFO
// would block forever (tinygltf's own FileExists already opens it), /dev/zero never ends. To tinygltf anything
// else does not exist.
bool regular_file_exists(const std::string& path, void*) {
    std::error_code ec;
    return fs::is_regular_file(path, ec);
}

bool read_regular_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void*) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
        if (err) *err += "File is not a regular file: " + path + "\n";
        return false;
    }
    return tinygltf::ReadWholeFile(out, err, path, nullptr);
}

tinygltf::Model parse(const fs::path& path) {
    const std::string file = path.string();
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error(file + ": file not found");
    if (fs::file_size(path, ec) == 0) throw Error(file + ": file is empty");
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&keep_encoded_image, nullptr);
    loader.SetFsCallbacks({&regular_file_exists, &tinygltf::ExpandFilePath, &read_regular_file,
                           &tinygltf::WriteWholeFile, nullptr});
    loader.SetStoreOriginalJSONForExtrasAndExtensions(true);
    tinygltf::Model model;
    std::string err, warn;
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    // Sniff the magic rather than trusting the extension: some tools write binary glTF as .gltf.
    char magic[4] = {0, 0, 0, 0};
    std::ifstream(path, std::ios::binary).read(magic, 4);
    const bool binary = std::string(magic, 4) == "glTF";
    // Our own pass over the JSON first: nesting depth (tinygltf converts `extras` recursively) and the schema
    // (tinygltf drops values of the wrong type silently).
    gltf::check_schema(parse_json_text(json_text(path, binary), file), file);
    bool ok = false;
    try {
        ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, file)
                    : loader.LoadASCIIFromFile(&model, &err, &warn, file);
    } catch (const std::exception& e) {
        throw Error(file + ": " + e.what());
    }
    // Missing external images are only a warning in tinygltf; we report them per material (as errors)
    // instead, so those lines are dropped here and the rest is passed on as one line.
    std::string kept;
    for (size_t pos = 0; pos < warn.size();) {
        size_t end = warn.find('\n', pos);
        if (end == std::string::npos) end = warn.size();
        const std::string line = warn.substr(pos, end - pos);
        if (!line.empty() && line.find("image") == std::string::npos)
            kept += (kept.empty() ? "" : "; ") + line;
        pos = end + 1;
    }
    if (!kept.empty()) spdlog::warn("{}: {}", file, kept);
    if (!ok || !err.empty()) throw Error(file + ": " + (err.empty() ? "cannot parse glTF" : one_line(err)));
    return model;
}

Mat4 local_transform(const Context& ctx, const tinygltf::Node& n, const std::string& label) {
    const std::string where = ctx.file + ": node '" + label + "'";
    if (n.matrix.size() == 16) return Mat4::from_column_major(n.matrix.data());
    if (!n.matrix.empty()) throw Error(where + ": matrix must have 16 numbers");
    Mat4 t, r, s;
    if (n.translation.size() == 3)
        t = Mat4::translation(n.translation[0], n.translation[1], n.translation[2]);
    if (n.rotation.size() == 4) {
        // The spec asks for a unit quaternion; exporters round. A zero one was refused by check_schema;
        // others are normalised (as Blender does), with one warning per file when clearly not unit.
        const double norm = std::sqrt(n.rotation[0] * n.rotation[0] + n.rotation[1] * n.rotation[1] +
                                      n.rotation[2] * n.rotation[2] + n.rotation[3] * n.rotation[3]);
        if (std::abs(norm - 1.0) > 1e-3 && ctx.clamped.insert("rotation").second)
            spdlog::warn(
                "{}: node '{}': rotation quaternion has length {}, normalised (further ones in this file "
                "are not reported)",
                ctx.file, label, norm);
        r = Mat4::rotation_quat(n.rotation[0], n.rotation[1], n.rotation[2], n.rotation[3]);
    }
    if (n.scale.size() == 3) s = Mat4::scale(n.scale[0], n.scale[1], n.scale[2]);
    return t * r * s;
}

struct CameraCandidate {
    std::string node_name, camera_name;
    int camera = -1;
    Mat4 world;
    int node = -1;
    bool moving = false;  // under an animated node
};

class Flattener {
  public:
    // `animation`: where objects under an animated node are recorded (null: the file has no animation).
    Flattener(const Context& ctx, Scene& scene, SceneAnimation* animation)
        : m_ctx(ctx), m_scene(scene), m_materials(ctx, scene), m_animation(animation) {
        m_targeted.assign(ctx.model.nodes.size(), 0);
        if (animation)
            for (const AnimationChannel& c : animation->animation.channels) m_targeted[size_t(c.node)] = 1;
    }

    void node(int index, const Mat4& parent, std::set<int>& path, bool parent_moving = false) {
        const auto& model = m_ctx.model;
        if (index < 0 || size_t(index) >= model.nodes.size())
            throw Error(m_ctx.file + ": node " + std::to_string(index) + " does not exist");
        if (!path.insert(index).second)
            throw Error(m_ctx.file + ": node " + std::to_string(index) +
                        " is its own ancestor (cycle in children)");
        const auto& n = model.nodes[size_t(index)];
        const std::string label = n.name.empty() ? fmt::format("#{}", index) : n.name;
        const Mat4 world = parent * local_transform(m_ctx, n, label);
        if (!world.is_finite()) throw Error(m_ctx.file + ": node '" + label + "': transform is not finite");
        const bool moving = parent_moving || m_targeted[size_t(index)];
        m_moving = moving;
        if (n.mesh >= 0) mesh(n, index, label, world);
        if (n.camera >= 0) {
            if (size_t(n.camera) >= model.cameras.size())
                throw Error(m_ctx.file + ": node '" + label + "': camera " + std::to_string(n.camera) +
                            " does not exist");
            cameras.push_back({n.name, model.cameras[size_t(n.camera)].name, n.camera, world, index, moving});
        }
        light(n, index, label, world);
        for (int c : n.children) node(c, world, path, moving);
        path.erase(index);
    }

    std::vector<CameraCandidate> cameras;

  private:
    void mesh(const tinygltf::Node& n, int node_index, const std::string& label, const Mat4& world) {
        const auto& model = m_ctx.model;
        if (size_t(n.mesh) >= model.meshes.size())
            throw Error(m_ctx.file + ": node '" + label + "': mesh " + std::to_string(n.mesh) +
                        " does not exist");
        const auto& gm = model.meshes[size_t(n.mesh)];
        const std::string mesh_name = gm.name.empty() ? fmt::format("#{}", n.mesh) : gm.name;
        for (size_t p = 0; p < gm.primitives.size(); ++p) {
            const auto& prim = gm.primitives[p];
            const std::string what_mesh = "of mesh '" + mesh_name + "'";
            if (prim.mode != TINYGLTF_MODE_TRIANGLES) {
                if (!m_warned_mode)
                    spdlog::warn(
                        "{}: mesh '{}': primitive mode {} is not TRIANGLES; such primitives are skipped",
                        m_ctx.file, mesh_name, prim.mode);
                m_warned_mode = true;
                continue;
            }
            auto pos_it = prim.attributes.find("POSITION");
            if (pos_it == prim.attributes.end())
                throw Error(m_ctx.file + ": mesh '" + mesh_name + "' primitive " + std::to_string(p) +
                            ": has no POSITION attribute");
            Mesh mesh;
            mesh.name = n.name.empty() ? mesh_name : n.name;
            mesh.positions = gltf::read_vec3(m_ctx, pos_it->second, "POSITION " + what_mesh);
            if (auto it = prim.attributes.find("NORMAL"); it != prim.attributes.end())
                mesh.normals = gltf::read_vec3(m_ctx, it->second, "NORMAL " + what_mesh);
            if (auto it = prim.attributes.find("TEXCOORD_0"); it != prim.attributes.end())
                mesh.uvs = gltf::read_texcoords(m_ctx, it->second, "TEXCOORD_0 " + what_mesh);
            if (prim.indices >= 0) {
                mesh.indices = gltf::read_indices(m_ctx, prim.indices, "indices " + what_mesh);
            } else {
                mesh.indices.resize(mesh.positions.size() - mesh.positions.size() % 3);
                for (size_t i = 0; i < mesh.indices.size(); ++i) mesh.indices[i] = uint32_t(i);
            }
            const std::string where = m_ctx.file + ": mesh '" + mesh_name + "' (node '" + label + "')";
            if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size())
                throw Error(where + ": NORMAL has " + std::to_string(mesh.normals.size()) +
                            " elements, POSITION " + std::to_string(mesh.positions.size()));
            if (!mesh.uvs.empty() && mesh.uvs.size() != mesh.positions.size())
                throw Error(where + ": TEXCOORD_0 has " + std::to_string(mesh.uvs.size()) +
                            " elements, POSITION " + std::to_string(mesh.positions.size()));
            validate_mesh(
                mesh, where + ", POSITION accessor " + std::to_string(pos_it->second) +
                          (prim.indices >= 0 ? ", indices accessor " + std::to_string(prim.indices) : ""));
            if (mesh.indices.empty()) continue;

            mesh.material = m_materials.material(prim.material);
            const Material& mat = m_scene.materials[size_t(mesh.material)];
            if (mat.is_volume) {
                VolumeInstance v;
                v.name = n.name.empty() ? label : n.name;
                v.local_to_world = world;
                mesh_bounds(mesh, v.local_min, v.local_max);
                v.extras_json = model.nodes[size_t(node_index)].extras_json_string;
                v.declared_in = m_ctx.file;
                check_volume_placement(v, m_ctx.file + ": volume '" + v.name + "' (node '" + label + "')");
                if (m_moving) m_animation->volumes.push_back({m_scene.volumes.size(), node_index});
                m_scene.volumes.push_back(std::move(v));
                continue;
            }
            if (mat.normal_texture >= 0 && mesh.normals.empty()) generate_smooth_normals(mesh);
            if (std::abs(world.determinant3()) < 1e-30) {
                spdlog::warn("{}: node '{}' has a singular transform; its mesh is skipped", m_ctx.file,
                             label);
                continue;
            }
            if (m_moving) m_animation->meshes.push_back({m_scene.meshes.size(), node_index, mesh});
            transform_mesh(mesh, world, where);
            m_scene.meshes.push_back(std::move(mesh));
        }
    }

    void light(const tinygltf::Node& n, int node_index, const std::string& label, const Mat4& world) {
        auto it = n.extensions.find("KHR_lights_punctual");
        if (it == n.extensions.end() || !it->second.Has("light")) return;
        const auto& lv = it->second.Get("light");
        const int li = lv.IsNumber() ? int(lv.GetNumberAsDouble()) : -1;
        if (li < 0 || size_t(li) >= m_ctx.model.lights.size())
            throw Error(m_ctx.file + ": node '" + label + "': KHR_lights_punctual.light " +
                        std::to_string(li) + " does not exist");
        const auto& gl = m_ctx.model.lights[size_t(li)];
        PunctualLight l;
        l.name = gl.name.empty() ? label : gl.name;
        if (gl.type == "point") {
            l.type = PunctualType::Point;
        } else if (gl.type == "spot") {
            l.type = PunctualType::Spot;
            l.inner_cone = float(gl.spot.innerConeAngle);
            l.outer_cone = float(gl.spot.outerConeAngle);
        } else if (gl.type == "directional") {
            l.type = PunctualType::Directional;
        } else {
            throw Error(m_ctx.file + ": light '" + l.name + "': unknown type '" + gl.type + "'");
        }
        const Rgb color =
            gl.color.size() >= 3
                ? gltf::clamp_field(m_ctx, Rgb(float(gl.color[0]), float(gl.color[1]), float(gl.color[2])),
                                    0.0f, 1.0f, "KHR_lights_punctual.color", "light '" + l.name + "'")
                : Rgb(1.0f);
        l.intensity = color * float(gl.intensity);
        l.position = world.transform_point(Vec3(0.0f));
        const Vec3 d = world.transform_vector(Vec3(0, 0, -1));
        if (!(length(d) > 0.0f))
            throw Error(m_ctx.file + ": node '" + label + "': light direction is degenerate");
        l.direction = normalize(d);
        if (!is_finite(l.direction))
            throw Error(m_ctx.file + ": node '" + label + "': light direction is not finite as a float");
        if (!is_finite(l.intensity))
            throw Error(m_ctx.file + ": light '" + l.name +
                        "': colour or intensity is not finite as a float");
        check_world_point(l.position, m_ctx.file + ": light '" + l.name + "' (node '" + label + "')",
                          "position");
        if (m_moving) m_animation->lights.push_back({m_scene.lights.size(), node_index});
        m_scene.lights.push_back(l);
    }

    const Context& m_ctx;
    Scene& m_scene;
    gltf::MaterialTable m_materials;
    SceneAnimation* m_animation;
    std::vector<char> m_targeted;  // per node: a channel of the animation targets it
    bool m_moving = false;         // the node being flattened is under an animated node
    bool m_warned_mode = false;
};

Camera make_camera(const Context& ctx, const CameraCandidate& c) {
    const auto& gc = ctx.model.cameras[size_t(c.camera)];
    const std::string label = c.node_name.empty() ? gc.name : c.node_name;
    if (gc.type == "orthographic")
        throw Error(ctx.file + ": camera '" + label + "': orthographic cameras are not supported yet");
    if (gc.type != "perspective")
        throw Error(ctx.file + ": camera '" + label + "': unknown type '" + gc.type + "'");
    Camera cam;
    cam.name = label;
    place_camera(cam, c.world, ctx.file + ": camera '" + label + "'");
    cam.yfov = float(gc.perspective.yfov);
    cam.aspect = float(gc.perspective.aspectRatio);
    if (!(cam.yfov > 0.0f && cam.yfov < k_pi))
        throw Error(ctx.file + ": camera '" + label + "': perspective.yfov must be in (0, pi)");
    if (!(cam.aspect >= 0.0f && std::isfinite(cam.aspect)))
        throw Error(ctx.file + ": camera '" + label + "': perspective.aspectRatio must be positive");
    return cam;
}

void apply_extras(const Context& ctx, const tinygltf::Value& extras, Scene& scene) {
    if (!extras.IsObject()) return;
    auto get_int = [&](const char* key, int& out, int lo) {
        if (!extras.Has(key)) return;
        const auto& v = extras.Get(key);
        if (!v.IsNumber() || v.GetNumberAsDouble() < lo || v.GetNumberAsDouble() > 1e9 ||
            v.GetNumberAsDouble() != std::floor(v.GetNumberAsDouble()))
            throw Error(ctx.file + ": scene extras." + key +
                        ": expected an integer >= " + std::to_string(lo));
        out = int(v.GetNumberAsDouble());
    };
    get_int("width", scene.settings.width, 1);
    get_int("height", scene.settings.height, 1);
    get_int("spp", scene.settings.spp, 1);
    get_int("max_depth", scene.settings.max_depth, 0);
    if (extras.Has("fps")) {
        const auto& f = extras.Get("fps");
        if (!f.IsNumber() || !(f.GetNumberAsDouble() > 0) || !(f.GetNumberAsDouble() <= 1000))
            throw Error(ctx.file + ": scene extras.fps: expected a number of frames per second in (0, 1000]");
        scene.settings.fps = f.GetNumberAsDouble();
    }
    if (extras.Has("transparent")) {
        const auto& t = extras.Get("transparent");
        if (!t.IsBool()) throw Error(ctx.file + ": scene extras.transparent: expected true or false");
        scene.settings.transparent = t.Get<bool>();
    }
    if (extras.Has("background")) {
        const auto& b = extras.Get("background");
        bool ok = b.IsArray() && b.ArrayLen() == 3;
        for (int k = 0; ok && k < 3; ++k) ok = b.Get(k).IsNumber();
        if (!ok) throw Error(ctx.file + ": scene extras.background: expected an array of 3 numbers");
        for (int k = 0; k < 3; ++k) scene.environment.color[k] = float(b.Get(k).GetNumberAsDouble());
        if (!is_finite(scene.environment.color) || min_component(scene.environment.color) < 0)
            throw Error(ctx.file + ": scene extras.background: expected 3 finite radiances >= 0");
    }
}

}  // namespace

void load_gltf(const fs::path& path, const LoadOptions& options, Scene& scene, const Mat4& placement) {
    const tinygltf::Model model = parse(path);
    const Context ctx{model, path.string()};
    for (const auto& b : model.buffers)
        if (!b.uri.empty() && b.uri.rfind("data:", 0) != 0) scene.files.push_back(path.parent_path() / b.uri);

    std::vector<int> roots;
    if (!model.scenes.empty()) {
        const int s = model.defaultScene >= 0 ? model.defaultScene : 0;
        if (size_t(s) >= model.scenes.size())
            throw Error(ctx.file + ": scene " + std::to_string(s) + " does not exist");
        roots = model.scenes[size_t(s)].nodes;
        apply_extras(ctx, model.scenes[size_t(s)].extras, scene);
    } else {
        // No `scenes`: every node that is nobody's child is a root.
        std::vector<bool> child(model.nodes.size(), false);
        for (const auto& n : model.nodes)
            for (int c : n.children)
                if (c >= 0 && size_t(c) < child.size()) child[size_t(c)] = true;
        for (size_t i = 0; i < child.size(); ++i)
            if (!child[i]) roots.push_back(int(i));
    }

    auto animation = std::make_shared<SceneAnimation>();
    const bool animated = gltf::read_animation(ctx, options.animation_name, animation->animation, animation->names);
    if (animated && scene.animation) {
        spdlog::warn("{}: the scene already has an animation (from {}); this file's animations are ignored", ctx.file,
                     scene.animation->file);
    }
    const bool keep = animated && !scene.animation;
    if (keep) {
        animation->file = ctx.file;
        animation->nodes = gltf::rest_nodes(ctx);
        animation->placement = placement;
    }
    Flattener flat(ctx, scene, keep ? animation.get() : nullptr);
    std::set<int> path_nodes;
    for (int r : roots) flat.node(r, placement, path_nodes);

    const auto& cands = flat.cameras;
    size_t chosen = cands.size();
    if (!options.camera_name.empty()) {
        for (size_t i = 0; i < cands.size() && chosen == cands.size(); ++i)
            if (cands[i].node_name == options.camera_name || cands[i].camera_name == options.camera_name)
                chosen = i;
        if (chosen == cands.size()) {
            std::string names;
            for (const auto& c : cands)
                names += (names.empty() ? "" : ", ") + std::string("'") +
                         (c.node_name.empty() ? c.camera_name : c.node_name) + "'";
            throw Error(ctx.file + ": camera '" + options.camera_name +
                        "' not found (available: " + (names.empty() ? "none" : names) + ")");
        }
    } else if (!cands.empty() && scene.camera < 0) {
        chosen = 0;
    }
    for (size_t i = 0; i < cands.size(); ++i) {
        const bool ortho = model.cameras[size_t(cands[i].camera)].type == "orthographic";
        if (ortho && i != chosen) {
            spdlog::warn("{}: orthographic camera '{}' is ignored", ctx.file, cands[i].node_name);
            continue;
        }
        if (keep && cands[i].moving) animation->cameras.push_back({scene.cameras.size(), cands[i].node});
        scene.cameras.push_back(make_camera(ctx, cands[i]));
        if (i == chosen) scene.camera = int(scene.cameras.size()) - 1;
    }
    if (keep) scene.animation = std::move(animation);
}

}  // namespace npt::scene
