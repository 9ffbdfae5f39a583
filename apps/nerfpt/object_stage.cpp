#include "object_stage.h"

#include <fmt/format.h>

#include <chrono>

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
    const bool metric = height_m > 0;
    const double metres_per_unit = metric ? height_m / g.height : 1.0;  // object units per capture unit
    nerf::ObjectFrame f;
    Mat4& m = f.object_to_world;
    const Vector3d axes[3] = {g.x_axis, g.y_axis, g.up};
    for (size_t row = 0; row < 3; ++row) {
        for (size_t c = 0; c < 3; ++c) m.m[row][c] = axes[c][long(row)] / metres_per_unit;
        m.m[row][3] = g.base_center[long(row)];
    }
    for (int a = 0; a < 3; ++a) {
        f.box_min[a] = float(g.box_min[a] * metres_per_unit);
        f.box_max[a] = float(g.box_max[a] * metres_per_unit);
    }
    f.metric = metric;
    r.frame = f;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    r.record = {{"found", true},
                {"up", array(g.up)},
                {"x_axis", array(g.x_axis)},
                {"base_center", array(g.base_center)},
                {"box", {{"min", array(g.box_min)}, {"max", array(g.box_max)}}},
                {"height", g.height},
                {"fixation", array(g.fixation)},
                {"plane_inliers", g.plane_inliers},
                {"plane_candidates", g.plane_candidates},
                {"seed_points", g.seed_points},
                {"metric", metric},
                {"height_m", metric ? nlohmann::json(height_m) : nlohmann::json(nullptr)},
                {"metres_per_unit", metric ? nlohmann::json(metres_per_unit) : nlohmann::json(nullptr)},
                {"model_frame", nerf::object_frame_to_json(f)},
                {"seconds", seconds}};
    const Vector3d size = (g.box_max - g.box_min) * metres_per_unit;
    r.line = fmt::format(
        "object: up ({:.3f}, {:.3f}, {:.3f}), {} of {} points on the supporting plane, {} on the object; box "
        "{:.3g} x {:.3g} x {:.3g} {}",
        g.up.x(), g.up.y(), g.up.z(), g.plane_inliers, g.plane_candidates, g.seed_points, size.x(), size.y(),
        size.z(),
        metric ? fmt::format("m (--height {} m)", height_m)
               : "capture units (no --height: the model stands in the capture's units, not metres)");
    return r;
}

std::optional<nerf::ObjectFrame> object_frame_of_record(const nlohmann::json& record) {
    if (!record.is_object() || !record.value("found", false) || !record.contains("model_frame")) return std::nullopt;
    return nerf::object_frame_from_json(record["model_frame"], "capture.json: object.model_frame");
}

bool attach_object_frame(const fs::path& path, const nerf::ObjectFrame& frame) {
    nerf::NerfModel m = nerf::load_model(path);
    if (m.object && nerf::object_frame_to_json(*m.object) == nerf::object_frame_to_json(frame)) return false;
    m.object = frame;
    nerf::save_model(path, m, /*with_training=*/true);
    return true;
}

}  // namespace npt::cli
