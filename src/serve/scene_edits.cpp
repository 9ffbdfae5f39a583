#include "serve/scene_edits.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "scene/mesh_utils.h"

namespace npt::serve {
using json = nlohmann::json;

Mat4 Trs::matrix() const {
    return Mat4::translation(translation[0], translation[1], translation[2]) *
           Mat4::rotation_quat(rotation[0], rotation[1], rotation[2], rotation[3]) *
           Mat4::scale(scale[0], scale[1], scale[2]);
}

Trs decompose(const Mat4& m) {
    Trs t;
    t.translation = {m.m[0][3], m.m[1][3], m.m[2][3]};
    double r[3][3];
    for (int c = 0; c < 3; ++c) {
        const double len = std::sqrt(m.m[0][c] * m.m[0][c] + m.m[1][c] * m.m[1][c] + m.m[2][c] * m.m[2][c]);
        t.scale[c] = len;
        for (int k = 0; k < 3; ++k) r[k][c] = len > 0 ? m.m[k][c] / len : (k == c ? 1.0 : 0.0);
    }
    if (m.determinant3() < 0) {  // a mirror: folded into the x scale
        t.scale[0] = -t.scale[0];
        for (int k = 0; k < 3; ++k) r[k][0] = -r[k][0];
    }
    // Rotation matrix to quaternion (Shepperd's method); the columns are re-orthonormalised first so that a
    // sheared matrix yields a valid rotation.
    const double tr = r[0][0] + r[1][1] + r[2][2];
    double x, y, z, w;
    if (tr > 0) {
        const double s = std::sqrt(tr + 1.0) * 2;
        w = 0.25 * s, x = (r[2][1] - r[1][2]) / s, y = (r[0][2] - r[2][0]) / s, z = (r[1][0] - r[0][1]) / s;
    } else if (r[0][0] > r[1][1] && r[0][0] > r[2][2]) {
        const double s = std::sqrt(1.0 + r[0][0] - r[1][1] - r[2][2]) * 2;
        w = (r[2][1] - r[1][2]) / s, x = 0.25 * s, y = (r[0][1] + r[1][0]) / s, z = (r[0][2] + r[2][0]) / s;
    } else if (r[1][1] > r[2][2]) {
        const double s = std::sqrt(1.0 + r[1][1] - r[0][0] - r[2][2]) * 2;
        w = (r[0][2] - r[2][0]) / s, x = (r[0][1] + r[1][0]) / s, y = 0.25 * s, z = (r[1][2] + r[2][1]) / s;
    } else {
        const double s = std::sqrt(1.0 + r[2][2] - r[0][0] - r[1][1]) * 2;
        w = (r[1][0] - r[0][1]) / s, x = (r[0][2] + r[2][0]) / s, y = (r[1][2] + r[2][1]) / s, z = 0.25 * s;
    }
    const double n = std::sqrt(x * x + y * y + z * z + w * w);
    if (n > 0 && std::isfinite(n)) t.rotation = {x / n, y / n, z / n, w / n};
    return t;
}

scene::Camera camera_from_message(const CameraMsg& m) {
    scene::Camera c;
    c.name = "viewer";
    c.position = Vec3(float(m.position[0]), float(m.position[1]), float(m.position[2]));
    const Vec3 f = normalize(Vec3(float(m.forward[0]), float(m.forward[1]), float(m.forward[2])));
    const Vec3 up = Vec3(float(m.up[0]), float(m.up[1]), float(m.up[2]));
    c.forward = f;
    c.right = normalize(cross(f, up));
    c.up = cross(c.right, f);
    c.yfov = float(m.fov_deg * 3.14159265358979323846 / 180.0);
    return c;
}

void place_volume(scene::VolumeInstance& v, const Trs& trs) {
    scene::VolumeInstance moved = v;
    moved.local_to_world = trs.matrix();
    scene::check_volume_placement(moved, "volume '" + v.name + "'");
    v.local_to_world = moved.local_to_world;
}

json volume_extras(const scene::VolumeInstance& v) {
    if (v.extras_json.empty()) return json::object();
    const json e = json::parse(v.extras_json, nullptr, false);
    if (!e.is_object() || !e.contains("volume") || !e["volume"].is_object()) return json::object();
    return e["volume"];
}

bool edit_volume_fill(scene::VolumeInstance& v, const VolumeMsg& m) {
    json e = v.extras_json.empty() ? json::object() : json::parse(v.extras_json, nullptr, false);
    if (!e.is_object()) e = json::object();
    json& vol = e["volume"];
    if (!vol.is_object()) vol = json::object();
    const json before = vol;
    if (m.density_scale) vol["density_scale"] = *m.density_scale;
    if (m.emission_scale) vol["emission_scale"] = *m.emission_scale;
    if (m.crop_clear) vol.erase("crop");
    if (m.crop) vol["crop"] = {{"min", m.crop->first}, {"max", m.crop->second}};
    if (m.shading) vol["shading"] = *m.shading;
    if (vol == before) return false;
    v.extras_json = e.dump();
    return true;
}

json describe_camera(const scene::Camera& c) {
    return {{"name", c.name},
            {"position", {c.position.x, c.position.y, c.position.z}},
            {"forward", {c.forward.x, c.forward.y, c.forward.z}},
            {"up", {c.up.x, c.up.y, c.up.z}},
            {"fov_deg", c.yfov * 180.0 / 3.14159265358979323846}};
}

json describe_scene(const scene::Scene& scene, size_t file_cameras, const std::vector<double>& light_scales) {
    json cams = json::array();
    for (size_t i = 0; i < std::min(file_cameras, scene.cameras.size()); ++i) cams.push_back(describe_camera(scene.cameras[i]));
    json vols = json::array();
    for (const scene::VolumeInstance& v : scene.volumes) {
        const Trs t = decompose(v.local_to_world);
        const json extras = volume_extras(v);
        const std::string file = extras.value("file", std::string());
        const bool nerf = file.size() > 4 && file.substr(file.size() - 4) == ".npt";
        json d = {{"name", v.name},
                  {"file", file},
                  {"nerf", nerf},
                  {"translation", t.translation},
                  {"rotation", t.rotation},
                  {"scale", t.scale},
                  {"local_min", {v.local_min.x, v.local_min.y, v.local_min.z}},
                  {"local_max", {v.local_max.x, v.local_max.y, v.local_max.z}},
                  {"density_scale", extras.value("density_scale", 1.0)},
                  {"emission_scale", extras.value("emission_scale", 1.0)},
                  {"shading", extras.value("shading", std::string(nerf ? "auto" : "emissive"))}};
        if (extras.contains("crop")) d["crop"] = extras["crop"];
        vols.push_back(std::move(d));
    }
    json lights = json::array();
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        const scene::PunctualLight& l = scene.lights[i];
        lights.push_back({{"name", l.name},
                          {"type", l.type == scene::PunctualType::Point ? "point"
                                   : l.type == scene::PunctualType::Spot ? "spot" : "directional"},
                          {"intensity_scale", i < light_scales.size() ? light_scales[i] : 1.0}});
    }
    return {{"cameras", cams}, {"volumes", vols}, {"lights", lights}};
}

}  // namespace npt::serve
