#include "nerf/object_frame.h"

#include <nlohmann/json.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace npt::nerf {

namespace {

constexpr int k_object_frame_version = 1;

double column_norm(const Mat4& m, int c) {
    return std::sqrt(m.m[0][size_t(c)] * m.m[0][size_t(c)] + m.m[1][size_t(c)] * m.m[1][size_t(c)] +
                     m.m[2][size_t(c)] * m.m[2][size_t(c)]);
}

double column_dot(const Mat4& m, int a, int b) {
    double s = 0;
    for (size_t r = 0; r < 3; ++r) s += m.m[r][size_t(a)] * m.m[r][size_t(b)];
    return s;
}

Vec3 vec3_field(const nlohmann::json& j, const char* key, const std::string& where) {
    if (!j.is_object() || !j.contains(key) || !j[key].is_array() || j[key].size() != 3)
        throw Error(where + ": '" + key + "': expected 3 numbers");
    Vec3 v;
    for (int a = 0; a < 3; ++a) {
        const auto& x = j[key][size_t(a)];
        if (!x.is_number() || !std::isfinite(x.get<double>()) || std::abs(x.get<double>()) > 1e30)
            throw Error(where + ": '" + key + "': expected 3 finite numbers");
        v[a] = x.get<float>();
    }
    return v;
}

}  // namespace

double ObjectFrame::units_per_world() const { return 1.0 / column_norm(object_to_world, 0); }

nlohmann::json object_frame_to_json(const ObjectFrame& f) {
    nlohmann::json m = nlohmann::json::array();
    for (const auto& row : f.object_to_world.m)
        for (const double x : row) m.push_back(x);
    nlohmann::json j = {
        {"version", k_object_frame_version},
        {"object_to_world", m},
        {"box", {{"min", {f.box_min.x, f.box_min.y, f.box_min.z}}, {"max", {f.box_max.x, f.box_max.y, f.box_max.z}}}},
        {"metric", f.metric}};
    if (f.object_only) j["object_only"] = true;
    return j;
}

ObjectFrame object_frame_from_json(const nlohmann::json& j, const std::string& where) {
    if (!j.is_object()) throw Error(where + ": expected a JSON object");
    if (!j.contains("version") || !j["version"].is_number_integer() || j["version"].get<int64_t>() != k_object_frame_version)
        throw Error(where + ": 'version': this build reads version " + std::to_string(k_object_frame_version));
    ObjectFrame f;
    const auto it = j.find("object_to_world");
    if (it == j.end() || !it->is_array() || it->size() != 16)
        throw Error(where + ": 'object_to_world': expected 16 numbers (row-major)");
    for (size_t i = 0; i < 16; ++i) {
        const auto& x = (*it)[i];
        if (!x.is_number() || !std::isfinite(x.get<double>()) || std::abs(x.get<double>()) > 1e30)
            throw Error(where + ": 'object_to_world': expected 16 finite numbers");
        f.object_to_world.m[i / 4][i % 4] = x.get<double>();
    }
    const auto& m = f.object_to_world.m;
    if (m[3][0] != 0 || m[3][1] != 0 || m[3][2] != 0 || m[3][3] != 1)
        throw Error(where + ": 'object_to_world': the last row must be 0, 0, 0, 1");
    // A similarity: three orthogonal columns of one length, not mirrored.
    const double s = column_norm(f.object_to_world, 0);
    bool similarity = s > 1e-12 && f.object_to_world.determinant3() > 0;
    for (int c = 0; c < 3 && similarity; ++c) {
        similarity = std::abs(column_norm(f.object_to_world, c) - s) <= 1e-4 * s;
        for (int d = c + 1; d < 3 && similarity; ++d)
            similarity = std::abs(column_dot(f.object_to_world, c, d)) <= 1e-4 * s * s;
    }
    if (!similarity)
        throw Error(where + ": 'object_to_world': not a rotation with one uniform scale (and no mirroring)");
    if (!j.contains("box") || !j["box"].is_object()) throw Error(where + ": 'box': expected {\"min\": [...], \"max\": [...]}");
    f.box_min = vec3_field(j["box"], "min", where + ": box");
    f.box_max = vec3_field(j["box"], "max", where + ": box");
    for (int a = 0; a < 3; ++a)
        if (!(f.box_max[a] > f.box_min[a])) throw Error(where + ": 'box': max must exceed min on every axis");
    if (j.contains("metric")) {
        if (!j["metric"].is_boolean()) throw Error(where + ": 'metric': expected true or false");
        f.metric = j["metric"].get<bool>();
    }
    if (j.contains("object_only")) {
        if (!j["object_only"].is_boolean()) throw Error(where + ": 'object_only': expected true or false");
        f.object_only = j["object_only"].get<bool>();
    }
    return f;
}

Vec3 local_to_object(Vec3 l) { return {l.x, -l.z, l.y}; }
Vec3 object_to_local(Vec3 o) { return {o.x, o.z, -o.y}; }

void object_local_box(const ObjectFrame& f, Vec3* lo, Vec3* hi) {
    const Vec3 a = object_to_local(f.box_min), b = object_to_local(f.box_max);
    *lo = vmin(a, b);
    *hi = vmax(a, b);
}

LocalToModel object_local_to_model(const ObjectFrame& f, const Mat4& world_to_model) {
    Mat4 local_to_obj;  // rows: object = (x, -z, y)
    local_to_obj.m = {{{1, 0, 0, 0}, {0, 0, -1, 0}, {0, 1, 0, 0}, {0, 0, 0, 1}}};
    const Mat4 a = world_to_model * f.object_to_world * local_to_obj;
    const Mat4 inv = a.inverse();
    LocalToModel l;
    for (size_t r = 0; r < 3; ++r) {
        l.row[r] = Vec3(float(a.m[r][0]), float(a.m[r][1]), float(a.m[r][2]));
        l.inv_row[r] = Vec3(float(inv.m[r][0]), float(inv.m[r][1]), float(inv.m[r][2]));
        l.offset[int(r)] = float(a.m[r][3]);
    }
    return l;
}

CropBox object_model_box(const ObjectFrame& f, const Mat4& world_to_model) {
    const Mat4 a = world_to_model * f.object_to_world;
    CropBox box{Vec3(INFINITY), Vec3(-INFINITY)};
    for (int c = 0; c < 8; ++c) {
        const Vec3 p = a.transform_point(Vec3(c & 1 ? f.box_max.x : f.box_min.x, c & 2 ? f.box_max.y : f.box_min.y,
                                              c & 4 ? f.box_max.z : f.box_min.z));
        box.min = vmin(box.min, p);
        box.max = vmax(box.max, p);
    }
    return box;
}

Mat4 model_to_object(const ObjectFrame& f, const Mat4& world_to_model) {
    return (world_to_model * f.object_to_world).inverse();
}

Vec3 object_box_centre_world(const ObjectFrame& f) {
    return f.object_to_world.transform_point((f.box_min + f.box_max) * 0.5f);
}

ObjectCut object_cut(const ObjectFrame& f, const Mat4& world_to_model) {
    const Mat4 to_object = model_to_object(f, world_to_model);
    ObjectCut cut;
    cut.active = true;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) cut.m[4 * r + c] = float(to_object.m[r][c]);
    cut.box_min = f.box_min;
    cut.box_max = f.box_max;
    return cut;
}

}  // namespace npt::nerf
