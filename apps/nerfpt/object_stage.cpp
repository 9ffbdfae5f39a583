#include "object_stage.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>

#include "capture/colmap_model.h"
#include "capture/subject/subject_geometry.h"
#include "capture/transforms_writer.h"
#include "core/error.h"
#include "nerf/model_file.h"

namespace npt::cli {
namespace fs = std::filesystem;
using capture::subject::Vector3d;

namespace {

Vector3d column(const Mat4& m, int c) { return {m.m[0][size_t(c)], m.m[1][size_t(c)], m.m[2][size_t(c)]}; }

Vector3d apply(const Mat4& m, const capture::Vec3d& p) {
    Vector3d r;
    for (size_t i = 0; i < 3; ++i) r[long(i)] = m.m[i][0] * p[0] + m.m[i][1] * p[1] + m.m[i][2] * p[2] + m.m[i][3];
    return r;
}

nlohmann::json array(const Vector3d& v) { return {v.x(), v.y(), v.z()}; }

Vector3d vector_of(const nlohmann::json& j, const char* key) {
    const nlohmann::json& a = j.at(key);
    return {a.at(0).get<double>(), a.at(1).get<double>(), a.at(2).get<double>()};
}

// What capture.json keeps of the geometry: enough to rebuild it (geometry_of_record) for the dense refinement.
nlohmann::json geometry_record(const capture::subject::SubjectGeometry& g) {
    return {{"found", true},
            {"up", array(g.up)},
            {"x_axis", array(g.x_axis)},
            {"base_center", array(g.base_center)},
            {"box", {{"min", array(g.box_min)}, {"max", array(g.box_max)}}},
            {"height", g.height},
            {"fixation", array(g.fixation)},
            {"scale", g.scale},
            {"ring_radius", g.ring_radius},
            {"top_reach", g.top_reach},
            {"plane_inliers", g.plane_inliers},
            {"plane_candidates", g.plane_candidates},
            {"seed_points", g.seed_points}};
}

capture::subject::SubjectGeometry geometry_of_record(const nlohmann::json& j) {
    capture::subject::SubjectGeometry g;
    g.up = vector_of(j, "up");
    g.x_axis = vector_of(j, "x_axis");
    g.y_axis = g.up.cross(g.x_axis);
    g.base_center = vector_of(j, "base_center");
    g.box_min = vector_of(j.at("box"), "min");
    g.box_max = vector_of(j.at("box"), "max");
    g.height = j.at("height").get<double>();
    g.fixation = vector_of(j, "fixation");
    g.scale = j.at("scale").get<double>();
    g.ring_radius = j.at("ring_radius").get<double>();
    g.top_reach = j.at("top_reach").get<double>();
    g.plane.normal = g.up;
    g.plane.d = -g.up.dot(g.base_center);
    return g;
}

// Object units per capture unit: 1 without --height (the record holds null then).
double metres_per_unit(const nlohmann::json& record) {
    const auto it = record.find("metres_per_unit");
    return it != record.end() && it->is_number() ? it->get<double>() : 1.0;
}

// The object frame of geometry g (metric when height_m > 0: scaled so that g.height is height_m) into the
// record's model_frame, metric, height_m and metres_per_unit.
void set_frame(nlohmann::json& record, const capture::subject::SubjectGeometry& g, double height_m) {
    const bool metric = height_m > 0;
    const double metres_per_unit = metric ? height_m / g.height : 1.0;  // object units per capture unit
    nerf::ObjectFrame f;
    const Vector3d axes[3] = {g.x_axis, g.y_axis, g.up};
    for (size_t row = 0; row < 3; ++row) {
        for (size_t c = 0; c < 3; ++c) f.object_to_world.m[row][c] = axes[c][long(row)] / metres_per_unit;
        f.object_to_world.m[row][3] = g.base_center[long(row)];
    }
    for (int a = 0; a < 3; ++a) {
        f.box_min[a] = float(g.box_min[a] * metres_per_unit);
        f.box_max[a] = float(g.box_max[a] * metres_per_unit);
    }
    f.metric = metric;
    record["metric"] = metric;
    record["height_m"] = metric ? nlohmann::json(height_m) : nlohmann::json(nullptr);
    record["metres_per_unit"] = metric ? nlohmann::json(metres_per_unit) : nlohmann::json(nullptr);
    record["model_frame"] = nerf::object_frame_to_json(f);
}

}  // namespace

ObjectStageResult object_stage(const fs::path& colmap_model, double height_m) {
    const auto start = std::chrono::steady_clock::now();
    const capture::ColmapModel model = capture::read_colmap_model(colmap_model);
    // The same normalisation transforms.json was written with (capture/transforms_writer.h): the default
    // settings; only the camera distance matters here, and `nerfpt poses` keeps the default.
    const capture::NerfPoses poses = capture::nerf_poses(model);
    std::vector<capture::subject::ViewRay> views;
    for (const capture::PosedFrame& f : poses.frames) {
        capture::subject::ViewRay v;
        v.origin = column(f.camera_to_world, 3);
        v.axis = -column(f.camera_to_world, 2).normalized();  // OpenGL camera: looks down -Z
        v.up = column(f.camera_to_world, 1).normalized();
        views.push_back(v);
    }
    std::vector<Vector3d> points;
    points.reserve(model.points.size());
    for (const capture::ColmapPoint3D& p : model.points) points.push_back(apply(poses.world_from_colmap, p.xyz));

    ObjectStageResult r;
    capture::subject::SubjectGeometry g;
    try {
        g = capture::subject::find_subject(points, views);
    } catch (const Error& e) {
        r.record = {{"found", false}, {"reason", e.what()}};
        r.line = std::string("object: not found (") + e.what() + "); the model keeps the capture's frame";
        return r;
    }
    r.record = geometry_record(g);
    r.record["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    set_frame(r.record, g, height_m);
    r.frame = object_frame_of_record(r.record);
    const Vector3d size = (g.box_max - g.box_min) * metres_per_unit(r.record);
    r.line = fmt::format(
        "object: up ({:.3f}, {:.3f}, {:.3f}), {} of {} points on the supporting plane, {} on the object; first box "
        "{:.3g} x {:.3g} x {:.3g} {} (from the sparse points; the trained model refines it)",
        g.up.x(), g.up.y(), g.up.z(), g.plane_inliers, g.plane_candidates, g.seed_points, size.x(), size.y(),
        size.z(),
        height_m > 0 ? fmt::format("m (--height {} m)", height_m)
                     : "capture units (no --height: the model stands in the capture's units, not metres)");
    return r;
}

std::optional<nerf::ObjectFrame> object_frame_of_record(const nlohmann::json& record) {
    if (!record.is_object() || !record.value("found", false) || !record.contains("model_frame")) return std::nullopt;
    return nerf::object_frame_from_json(record["model_frame"], "capture.json: object.model_frame");
}

std::optional<std::array<Vec3, 8>> subject_box_of_record(const nlohmann::json& record) {
    if (!record.is_object() || !record.value("found", false)) return std::nullopt;
    // The first box, from sparse points (kept under "sparse" once a model refined it): what a capture has
    // before its first training, so that a retrained capture draws the same rays.
    nlohmann::json sparse = record;
    if (const auto it = record.find("sparse"); it != record.end())
        for (const char* key : {"box", "height", "base_center"}) sparse[key] = (*it)[key];
    const capture::subject::SubjectGeometry g = geometry_of_record(sparse);
    // Widened: the refined boxes of the development captures are up to 1.3 times the first one across, and
    // the object's contact with the table and its top's haze are trained too.
    const Vector3d c = (g.box_min + g.box_max) * 0.5, half = (g.box_max - g.box_min) * 0.5;
    const double widen = 1.3, z_lo = g.box_min.z() - 0.05 * g.height, z_hi = g.box_max.z() + 0.1 * g.height;
    std::array<Vec3, 8> corners;
    for (int i = 0; i < 8; ++i) {
        const double x = c.x() + (i & 1 ? 1 : -1) * half.x() * widen,
                     y = c.y() + (i & 2 ? 1 : -1) * half.y() * widen;
        const Vector3d p = g.base_center + x * g.x_axis + y * g.y_axis + (i & 4 ? z_hi : z_lo) * g.up;
        corners[size_t(i)] = Vec3(float(p.x()), float(p.y()), float(p.z()));
    }
    return corners;
}

ObjectAttach attach_object(const fs::path& path, nlohmann::json& record, double height_m, bool retrained) {
    ObjectAttach out;
    if (!record.value("found", false)) return out;
    nerf::NerfModel m = nerf::load_model(path);
    const uint64_t steps = m.training ? m.training->adam.step : 0;
    const auto dense = record.find("dense");
    if (retrained || dense == record.end() || dense->value("steps", uint64_t(0)) != steps) {
        // The sparse geometry (kept under "sparse" once refined), refined by this model's occupancy grid.
        if (!record.contains("sparse"))
            record["sparse"] = {{"box", record["box"]}, {"height", record["height"]}, {"base_center", record["base_center"]}};
        nlohmann::json sparse = record;
        for (const char* key : {"box", "height", "base_center"}) sparse[key] = record["sparse"][key];
        const capture::subject::SubjectGeometry g = geometry_of_record(sparse);
        const nerf::OccupancyGridView view = m.occupancy.view();
        const std::vector<float>& density = m.occupancy.density();
        const float min_step = m.march_params().min_step;
        const Mat4& w2m = m.world_to_model;
        // The occupancy cell of cascade 0 in capture units: the model's map is a uniform scale.
        const double model_per_world = std::sqrt(w2m.m[0][0] * w2m.m[0][0] + w2m.m[1][0] * w2m.m[1][0] +
                                                 w2m.m[2][0] * w2m.m[2][0]);
        const double cell = 1.0 / (double(view.resolution) * model_per_world);
        const auto opacity = [&](const Vector3d& p) {
            const Vec3 mp = w2m.transform_point(Vec3(float(p.x()), float(p.y()), float(p.z())));
            const int c = view.cascade_of(mp);
            const int64_t i = view.cell_index(mp, c);
            if (i < 0) return 0.0;
            return nerf::occupancy_cell_opacity(density[size_t(i)], view.cascade_size(c), view.resolution, min_step);
        };
        const capture::subject::DenseBox d = capture::subject::refine_box_with_field(g, cell, opacity);
        const capture::subject::SubjectGeometry& r = d.geometry;
        record["dense"] = {{"found", d.found}, {"cells", d.cells}, {"cell", d.cell}, {"steps", steps}};
        record["box"] = {{"min", array(r.box_min)}, {"max", array(r.box_max)}};
        record["height"] = r.height;
        record["base_center"] = array(r.base_center);
        set_frame(record, r, height_m);
        out.record_changed = true;
        const double mpu = metres_per_unit(record);
        out.line = d.found ? fmt::format("object: the model's density gives a box of {:.3g} x {:.3g} x {:.3g} {} "
                                         "({} cells)",
                                         (r.box_max.x() - r.box_min.x()) * mpu, (r.box_max.y() - r.box_min.y()) * mpu,
                                         (r.box_max.z() - r.box_min.z()) * mpu, height_m > 0 ? "m" : "capture units",
                                         d.cells)
                           : "object: the model has no dense cell inside the first box; the first box stays";
    }
    auto frame = object_frame_of_record(record);
    // The record holds where the object is; whether the model was isolated since is the model's own.
    if (frame && m.object) frame->object_only = m.object->object_only;
    if (frame && !(m.object && nerf::object_frame_to_json(*m.object) == nerf::object_frame_to_json(*frame))) {
        m.object = frame;
        nerf::save_model(path, m, /*with_training=*/true);
        out.model_written = true;
    }
    return out;
}

}  // namespace npt::cli
