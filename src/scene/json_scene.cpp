#include "scene/json_scene.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "scene/gltf_loader.h"
#include "scene/mesh_utils.h"
#include "scene/obj_loader.h"
#include "scene/texture_utils.h"

namespace npt::scene {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Typed accessors that fail with "<file>: <field>: expected ..." so each message names exactly what is wrong.
class Reader {
  public:
    explicit Reader(std::string file) : m_file(std::move(file)) {}

    [[noreturn]] void fail(const std::string& field, const std::string& msg) const {
        throw Error(m_file + ": " + field + ": " + msg);
    }
    double number(const json& v, const std::string& field) const {
        if (!v.is_number()) fail(field, "expected a number");
        const double d = v.get<double>();
        if (!std::isfinite(d)) fail(field, "expected a finite number");
        return d;
    }
    int integer(const json& v, const std::string& field, int lo, int hi) const {
        if (!v.is_number_integer() || v.get<long long>() < lo || v.get<long long>() > hi)
            fail(field, "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
        return int(v.get<long long>());
    }
    std::string string(const json& v, const std::string& field) const {
        if (!v.is_string() || v.get<std::string>().empty()) fail(field, "expected a non-empty string");
        return v.get<std::string>();
    }
    std::vector<double> numbers(const json& v, const std::string& field, size_t n) const {
        const std::string expect = "expected an array of " + std::to_string(n) + " numbers";
        if (!v.is_array() || v.size() != n) fail(field, expect);
        std::vector<double> out;
        for (const auto& e : v) {
            if (!e.is_number() || !std::isfinite(e.get<double>())) fail(field, expect);
            out.push_back(e.get<double>());
        }
        return out;
    }
    Vec3 vec3(const json& v, const std::string& field) const {
        auto d = numbers(v, field, 3);
        const Vec3 out{float(d[0]), float(d[1]), float(d[2])};
        if (!is_finite(out)) fail(field, "expected 3 numbers within the range of a float");
        return out;
    }
    void check_keys(const json& obj, const std::string& field,
                    std::initializer_list<const char*> known) const {
        for (const auto& item : obj.items()) {
            const std::string& key = item.key();  // clang 14 cannot capture a structured binding
            if (std::none_of(known.begin(), known.end(), [&](const char* k) { return key == k; }))
                spdlog::warn("{}: {}{}: unknown key, ignored", m_file, field.empty() ? "" : field + ".", key);
        }
    }
    const std::string& file() const { return m_file; }

  private:
    std::string m_file;
};

json parse_file(const fs::path& path) {
    const std::string file = path.string();
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error(file + ": file not found");
    return read_json_file(path, /*comments=*/true);
}

Mat4 placement(const Reader& r, const json& inc, const std::string& field) {
    Mat4 t, rot, s;
    if (inc.contains("translation")) {
        auto v = r.numbers(inc["translation"], field + ".translation", 3);
        t = Mat4::translation(v[0], v[1], v[2]);
    }
    if (inc.contains("rotation")) {
        auto q = r.numbers(inc["rotation"], field + ".rotation", 4);
        if (q[0] == 0 && q[1] == 0 && q[2] == 0 && q[3] == 0)
            r.fail(field + ".rotation", "quaternion (x, y, z, w) must not be zero");
        rot = Mat4::rotation_quat(q[0], q[1], q[2], q[3]);
    }
    if (inc.contains("scale")) {
        auto v = r.numbers(inc["scale"], field + ".scale", 3);
        if (v[0] == 0 || v[1] == 0 || v[2] == 0) r.fail(field + ".scale", "components must not be zero");
        s = Mat4::scale(v[0], v[1], v[2]);
    }
    return t * rot * s;
}

// A volume declared in the JSON itself: the cube [-1, 1]^3 placed by translation/rotation/scale, filled as a
// glTF node's extras.volume would say (the fields are checked where the grid is loaded).
void read_volume(const Reader& r, const json& v, const std::string& field, const fs::path& json_path,
                 Scene& scene) {
    if (!v.is_object()) r.fail(field, "expected an object {\"file\": ..., \"translation\": ...}");
    r.check_keys(v, field,
                 {"name", "file", "translation", "rotation", "scale", "density_scale", "emission_scale",
                  "casts_shadows", "step_voxels", "crop", "shading"});
    if (!v.contains("file")) r.fail(field + ".file", "missing");
    VolumeInstance vol;
    vol.name = v.contains("name") ? r.string(v["name"], field + ".name") : field;
    vol.local_to_world = placement(r, v, field);
    vol.declared_in = json_path;
    json fill = v;
    for (const char* k : {"name", "translation", "rotation", "scale"}) fill.erase(k);
    vol.extras_json = json{{"volume", fill}}.dump();
    check_volume_placement(vol, r.file() + ": " + field);
    scene.volumes.push_back(std::move(vol));
}

void load_include(const Reader& r, const json& inc, const std::string& field, const fs::path& dir,
                  const std::string& animation_name,
                  Scene& scene) {
    std::string rel;
    Mat4 m;
    if (inc.is_string()) {
        rel = r.string(inc, field);
    } else if (inc.is_object()) {
        if (!inc.contains("file")) r.fail(field + ".file", "missing");
        rel = r.string(inc["file"], field + ".file");
        r.check_keys(inc, field, {"file", "translation", "rotation", "scale"});
        m = placement(r, inc, field);
    } else {
        r.fail(field, "expected a file name or an object {\"file\": ...}");
    }
    const fs::path p = dir / rel;
    std::error_code ec;
    if (!fs::exists(p, ec)) r.fail(field, "file '" + p.string() + "' not found");
    std::string ext = p.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    scene.files.push_back(p);
    if (ext != ".gltf" && ext != ".glb" && ext != ".obj")
        r.fail(field, "'" + rel + "': can include only .gltf, .glb and .obj files");
    // The included file's own error names it and its field; prefixed with ours, the line says which include
    // (and its placement) led there.
    try {
        if (ext == ".obj")
            load_obj(p, scene, m);
        else
            load_gltf(p, LoadOptions{"", animation_name}, scene, m);
    } catch (const Error& e) {
        r.fail(field, e.what());
    }
}

void read_camera(const Reader& r, const json& c, Scene& scene) {
    if (!c.is_object()) r.fail("camera", "expected an object");
    if (c.contains("name")) {
        r.check_keys(c, "camera", {"name"});
        const std::string name = r.string(c["name"], "camera.name");
        std::string names;
        for (size_t i = 0; i < scene.cameras.size(); ++i) {
            if (scene.cameras[i].name == name) {
                scene.camera = int(i);
                return;
            }
            names += (names.empty() ? "'" : ", '") + scene.cameras[i].name + "'";
        }
        r.fail("camera.name", "camera '" + name + "' not found in the included files (available: " +
                                  (names.empty() ? "none" : names) + ")");
    }
    r.check_keys(c, "camera", {"position", "look_at", "up", "yfov_deg", "aspect"});
    for (const char* key : {"position", "look_at"})
        if (!c.contains(key)) r.fail(std::string("camera.") + key, "missing (or give {\"name\": ...})");
    Camera cam;
    cam.name = "json";
    cam.position = r.vec3(c["position"], "camera.position");
    check_world_point(cam.position, r.file() + ": camera", "position");
    const Vec3 target = r.vec3(c["look_at"], "camera.look_at");
    const Vec3 up = c.contains("up") ? r.vec3(c["up"], "camera.up") : Vec3(0, 1, 0);
    const Vec3 f = target - cam.position;
    if (!(length(f) > 0.0f)) r.fail("camera.look_at", "must differ from camera.position");
    cam.forward = normalize(f);
    const Vec3 right = cross(cam.forward, up);
    if (!(length(right) > 1e-6f * length(up)))
        r.fail("camera.up", "must not be parallel to the view direction");
    cam.right = normalize(right);
    cam.up = cross(cam.right, cam.forward);
    if (c.contains("yfov_deg")) {
        const double deg = r.number(c["yfov_deg"], "camera.yfov_deg");
        if (!(deg > 0 && deg < 180)) r.fail("camera.yfov_deg", "expected degrees in (0, 180)");
        cam.yfov = float(deg * 3.14159265358979323846 / 180.0);
    }
    if (c.contains("aspect")) {
        cam.aspect = float(r.number(c["aspect"], "camera.aspect"));
        if (!(cam.aspect >= 0.0f) || !std::isfinite(cam.aspect))
            r.fail("camera.aspect", "expected width / height > 0 (or 0: the image's)");
    }
    scene.cameras.push_back(cam);
    scene.camera = int(scene.cameras.size()) - 1;
}

void read_environment(const Reader& r, const json& e, const fs::path& dir, Scene& scene) {
    if (!e.is_object()) r.fail("environment", "expected an object");
    r.check_keys(e, "environment", {"file", "strength", "rotation_deg"});
    if (e.contains("file")) {
        const fs::path p = dir / r.string(e["file"], "environment.file");
        try {
            scene.textures.push_back(make_texture(read_image(p, true), p.string()));
        } catch (const Error& err) {
            r.fail("environment.file", err.what());
        }
        scene.environment.texture = int(scene.textures.size()) - 1;
    }
    if (e.contains("strength")) {
        scene.environment.strength = float(r.number(e["strength"], "environment.strength"));
        if (scene.environment.strength < 0) r.fail("environment.strength", "must not be negative");
    }
    if (e.contains("rotation_deg"))
        scene.environment.rotation_y =
            float(r.number(e["rotation_deg"], "environment.rotation_deg") * 3.14159265358979323846 / 180.0);
}

void read_render(const Reader& r, const json& j, RenderSettings& s) {
    if (!j.is_object()) r.fail("render", "expected an object");
    r.check_keys(j, "render", {"width", "height", "spp", "max_depth", "seed", "transparent", "fps"});
    if (j.contains("fps")) {
        s.fps = r.number(j["fps"], "render.fps");
        if (!(s.fps > 0 && s.fps <= 1000)) r.fail("render.fps", "expected frames per second in (0, 1000]");
    }
    if (j.contains("width")) s.width = r.integer(j["width"], "render.width", 1, k_max_image_side);
    if (j.contains("height")) s.height = r.integer(j["height"], "render.height", 1, k_max_image_side);
    if (j.contains("spp")) s.spp = r.integer(j["spp"], "render.spp", 1, 1 << 24);
    if (j.contains("max_depth")) s.max_depth = r.integer(j["max_depth"], "render.max_depth", 0, 1024);
    if (j.contains("seed")) {
        if (!j["seed"].is_number_unsigned()) r.fail("render.seed", "expected a non-negative integer");
        s.seed = j["seed"].get<uint64_t>();
    }
    if (j.contains("transparent")) {
        if (!j["transparent"].is_boolean()) r.fail("render.transparent", "expected true or false");
        s.transparent = j["transparent"].get<bool>();
    }
}

}  // namespace

void load_json_scene(const fs::path& path, const LoadOptions& options, Scene& scene) {
    const json root = parse_file(path);
    const Reader r(path.string());
    if (!root.is_object()) r.fail("(top level)", "expected an object");
    r.check_keys(root, "", {"include", "volumes", "camera", "environment", "background", "render"});
    const fs::path dir = path.parent_path();

    if (root.contains("include")) {
        const json& inc = root["include"];
        if (!inc.is_array()) r.fail("include", "expected an array of files");
        for (size_t i = 0; i < inc.size(); ++i)
            load_include(r, inc[i], "include[" + std::to_string(i) + "]", dir, options.animation_name, scene);
    }
    if (root.contains("volumes")) {
        const json& vols = root["volumes"];
        if (!vols.is_array()) r.fail("volumes", "expected an array of volumes");
        for (size_t i = 0; i < vols.size(); ++i)
            read_volume(r, vols[i], "volumes[" + std::to_string(i) + "]", path, scene);
    }
    // The JSON's own settings override whatever the included files said.
    if (root.contains("background")) {
        scene.environment.color = r.vec3(root["background"], "background");
        if (min_component(scene.environment.color) < 0) r.fail("background", "radiance must not be negative");
    }
    if (root.contains("environment")) read_environment(r, root["environment"], dir, scene);
    if (root.contains("render")) read_render(r, root["render"], scene.settings);
    if (!options.camera_name.empty()) {
        read_camera(r, json{{"name", options.camera_name}}, scene);
    } else if (root.contains("camera")) {
        read_camera(r, root["camera"], scene);
    }
}

}  // namespace npt::scene
