// Where the subject of a capture is, from the cameras and COLMAP's sparse points alone: the point the cameras
// fixate, the plane it stands on, its up direction and a first box around it (issue 25). Pure functions in
// the capture's coordinates (transforms.json's): no images are read.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace npt::capture::subject {

using Eigen::Vector3d;

// One camera: its centre, its optical axis (unit, the direction it looks) and the image's up (unit).
struct ViewRay {
    Vector3d origin = Vector3d::Zero();
    Vector3d axis = Vector3d(0, 0, -1);
    Vector3d up = Vector3d(0, 1, 0);
};

// The point closest, in least squares, to every camera's optical axis (lines, not half-lines): the point a
// capture walks around. Throws npt::Error when fewer than two views are given or all axes are parallel.
Vector3d fixation_point(const std::vector<ViewRay>& views);

// n . x + d = 0 with |n| = 1; height(x) = n . x + d is the signed distance, positive on the cameras' side.
struct Plane {
    Vector3d normal = Vector3d(0, 0, 1);
    double d = 0;
    double height(const Vector3d& x) const { return normal.dot(x) + d; }
};

struct SubjectSettings {
    // The plane's normal must lie within this angle of the cameras' mean image up.
    double max_tilt_deg = 35.0;
    // RANSAC inlier distance as a fraction of the median camera distance from the fixation point (the capture's
    // scale); the final least-squares fit uses a third of it.
    double inlier_fraction = 0.006;
    int ransac_iterations = 3000;
    uint64_t seed = 1;
    // Seed points: above the plane by at least this fraction of the camera distance (off the plane's noise),
    // and linked to the points nearest the fixation axis by hops of at most link_fraction of it.
    double clearance_fraction = 0.012;
    double link_fraction = 0.05;
    // The box: these percentiles of the seed points (per horizontal axis; the top), widened on every side but
    // the base by margin_fraction of the box's largest extent.
    double low_percentile = 2.0, high_percentile = 98.0;
    double margin_fraction = 0.08;
};

struct SubjectGeometry {
    Vector3d fixation = Vector3d::Zero();
    double scale = 0;  // median camera distance from the fixation point (capture units)
    Plane plane;
    size_t plane_inliers = 0;     // points within the final inlier distance of the plane
    size_t plane_candidates = 0;  // points that could support a plane (within the search radius)
    // The object frame in capture coordinates: origin on the plane under the box's centre, z = up = the plane's
    // normal, x = the capture's x (or y) projected on the plane, y = z x x.
    Vector3d up = Vector3d::UnitZ(), x_axis = Vector3d::UnitX(), y_axis = Vector3d::UnitY();
    Vector3d base_center = Vector3d::Zero();
    // The box in the object frame (capture units): z from 0 (the plane) to the top.
    Vector3d box_min = Vector3d::Zero(), box_max = Vector3d::Zero();
    double height = 0;  // the seed points' high percentile above the plane (capture units), no margin
    size_t seed_points = 0;
    // Where the object was searched: within ring_fraction (0.6) of the cameras' ring radius of the vertical
    // through the fixation point, up to top_reach above the plane (capture units).
    double ring_radius = 0, top_reach = 0;

    Vector3d to_object(const Vector3d& p) const {
        const Vector3d q = p - base_center;
        return {x_axis.dot(q), y_axis.dot(q), up.dot(q)};
    }
    Vector3d from_object(const Vector3d& o) const { return base_center + o.x() * x_axis + o.y() * y_axis + o.z() * up; }
};

// The supporting plane by RANSAC over `points`: among planes whose normal lies within max_tilt_deg of the
// views' mean up, that have every camera and the fixation point on their upper side, the one with the most
// points within the inlier distance inside the cameras' ring (so that the table an object stands on wins over
// the floor seen beyond it), refined by least squares. Throws npt::Error when no such plane exists.
Plane fit_support_plane(const std::vector<Vector3d>& points, const std::vector<ViewRay>& views,
                        const Vector3d& fixation, double scale, const SubjectSettings& settings,
                        size_t* inliers = nullptr, size_t* candidates = nullptr);

// The whole chain: fixation point, plane, up, seed points (above the plane, connected to the points nearest
// the vertical through the fixation point), the box and the object frame. Throws npt::Error naming what is
// missing (too few views or points, no plane, nothing above it).
SubjectGeometry find_subject(const std::vector<Vector3d>& points, const std::vector<ViewRay>& views,
                             const SubjectSettings& settings = {});

// The box again from a dense field (a first model's density), not the sparse points: COLMAP's points on the
// object can be few (79 on a 22 cm object at --poses-quality fast), and their percentiles miss its top and
// sides. `opacity(p)` (p in capture coordinates) is the field's opacity across one cell of `cell` capture units.
// Cells above the plane by the clearance and inside the search cylinder whose opacity reaches `threshold` are
// flood-filled (26-neighbours) from the occupied cells inside the sparse box; the box becomes the component's
// extent plus one cell, from the plane up (the base stays the plane; the base centre moves under the new box).
struct DenseBoxSettings {
    double threshold = 0.5;
    double clearance_fraction = 0.012;  // as SubjectSettings's
    size_t max_cells = size_t(1) << 26;  // a coarser cell is used beyond this many
};
struct DenseBox {
    bool found = false;     // false: no occupied cell inside the sparse box (g is returned unchanged)
    size_t cells = 0;       // in the component
    double cell = 0;        // the cell size used, capture units
    SubjectGeometry geometry;  // g with the new box, height and base centre
};
DenseBox refine_box_with_field(const SubjectGeometry& g, double cell,
                               const std::function<double(const Vector3d&)>& opacity,
                               const DenseBoxSettings& settings = {});

}  // namespace npt::capture::subject
