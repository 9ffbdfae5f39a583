// Reading poses, Umeyama's alignment, per-camera errors and matching by name or time. The time-mapping search
// is in pose_time_mapping.cpp.
#include "capture/pose_alignment.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>

#include "capture/pose_alignment_detail.h"
#include "core/error.h"
#include "core/json_file.h"

namespace npt::capture {
namespace {

namespace fs = std::filesystem;
using Eigen::Matrix3d;
using Eigen::Vector3d;

CameraPose read_frame(const nlohmann::json& frame, size_t i, const std::string& file) {
    std::string where = file + ": frame " + std::to_string(i);
    if (!frame.is_object()) throw Error(where + ": must be an object");
    auto fp = frame.find("file_path");
    if (fp == frame.end() || !fp->is_string()) throw Error(where + ": 'file_path' missing or not a string");
    CameraPose pose;
    pose.name = fs::path(fp->get<std::string>()).filename().string();
    if (pose.name.empty()) throw Error(where + ": 'file_path' names no file");
    where += " ('" + pose.name + "')";
    auto tm = frame.find("transform_matrix");
    if (tm == frame.end()) throw Error(where + ": missing 'transform_matrix'");
    bool shape_ok = tm->is_array() && tm->size() == 4;
    for (size_t r = 0; shape_ok && r < 4; ++r) shape_ok = (*tm)[r].is_array() && (*tm)[r].size() == 4;
    if (!shape_ok) throw Error(where + ": 'transform_matrix' must be a 4x4 array of numbers");
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) {
            const auto& v = (*tm)[size_t(r)][size_t(c)];
            // nlohmann writes NaN as null: say so rather than "not a number".
            if (v.is_null())
                throw Error(where + ": 'transform_matrix' has null (NaN?) at row " + std::to_string(r));
            if (!v.is_number()) throw Error(where + ": 'transform_matrix' must be a 4x4 array of numbers");
            const double x = v.get<double>();
            if (!std::isfinite(x)) throw Error(where + ": 'transform_matrix' has NaN or Inf");
            if (c < 3)
                pose.rotation(r, c) = x;
            else
                pose.centre(r) = x;
        }
    // Errors are angles between rotations; a scaled or sheared matrix would make them meaningless.
    const double off =
        (pose.rotation.transpose() * pose.rotation - Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (off > 1e-3 || pose.rotation.determinant() < 0)
        throw Error(where + ": 'transform_matrix' 3x3 part is not a rotation (scaled, sheared or mirrored)");
    return pose;
}

double rotation_angle_deg(const Matrix3d& a, const Matrix3d& b) {
    // AngleAxis goes through a quaternion: accurate for small angles where acos((trace - 1) / 2) is not.
    return Eigen::AngleAxisd(a.transpose() * b).angle() * 180.0 / M_PI;
}

ErrorStats stats(std::vector<double> v) {
    ErrorStats s;
    if (v.empty()) return s;
    s.mean = std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
    s.max = *std::max_element(v.begin(), v.end());
    s.median = detail::median(v);
    return s;
}

}  // namespace

namespace detail {

double median(std::vector<double>& v) {
    const size_t n = v.size(), h = n / 2;
    std::nth_element(v.begin(), v.begin() + long(h), v.end());
    const double upper = v[h];
    if (n % 2) return upper;
    return 0.5 * (upper + *std::max_element(v.begin(), v.begin() + long(h)));
}

std::optional<Similarity> try_fit_similarity(const std::vector<Vector3d>& from,
                                             const std::vector<Vector3d>& to) {
    const size_t n = from.size();
    if (n < 3 || to.size() != n) return std::nullopt;
    Vector3d mean_from = Vector3d::Zero(), mean_to = Vector3d::Zero();
    for (size_t i = 0; i < n; ++i) {
        mean_from += from[i];
        mean_to += to[i];
    }
    mean_from /= double(n);
    mean_to /= double(n);
    double var_from = 0;
    Matrix3d cov = Matrix3d::Zero();
    for (size_t i = 0; i < n; ++i) {
        const Vector3d x = from[i] - mean_from;
        var_from += x.squaredNorm();
        cov += (to[i] - mean_to) * x.transpose();
    }
    var_from /= double(n);
    cov /= double(n);
    if (!cov.allFinite() || !std::isfinite(var_from)) return std::nullopt;
    const Eigen::JacobiSVD<Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Vector3d d = svd.singularValues();
    // Umeyama: the rotation is unique when the covariance has rank >= 2; coincident or collinear points on
    // either side make it rank <= 1.
    if (!(d(0) > 0) || d(1) <= 1e-9 * d(0)) return std::nullopt;
    Vector3d sign(1, 1, 1);
    if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) sign(2) = -1;
    Similarity s;
    s.rotation = svd.matrixU() * sign.asDiagonal() * svd.matrixV().transpose();
    s.scale = d.dot(sign) / var_from;
    s.translation = mean_to - s.scale * (s.rotation * mean_from);
    return s;
}

double trajectory_scale(const std::vector<Vector3d>& centres) {
    if (centres.empty()) return 0;
    Vector3d mean = Vector3d::Zero();
    for (const auto& c : centres) mean += c;
    mean /= double(centres.size());
    double sum = 0;
    for (const auto& c : centres) sum += (c - mean).squaredNorm();
    return std::sqrt(sum / double(centres.size()));
}

}  // namespace detail

std::vector<CameraPose> read_transforms_poses(const fs::path& json) {
    const std::string file = json.string();
    const nlohmann::json j = read_json_file(json);
    if (!j.is_object()) throw Error(file + ": must hold a JSON object with 'frames'");
    auto frames = j.find("frames");
    if (frames == j.end() || !frames->is_array()) throw Error(file + ": 'frames' missing or not an array");
    if (frames->empty()) throw Error(file + ": 'frames' is empty");
    std::vector<CameraPose> poses;
    for (size_t i = 0; i < frames->size(); ++i) poses.push_back(read_frame((*frames)[i], i, file));
    return poses;
}

std::vector<CameraPose> colmap_poses(const ColmapModel& model) {
    // OpenCV camera axes to OpenGL ones: y and z negated.
    const Matrix3d flip = Vector3d(1, -1, -1).asDiagonal();
    std::vector<CameraPose> poses;
    for (const ColmapImage& im : model.images) {
        const auto& q = im.qvec;
        const Matrix3d world_to_camera =
            Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
        const Vector3d t(im.tvec[0], im.tvec[1], im.tvec[2]);
        CameraPose p;
        p.name = im.name;
        p.rotation = world_to_camera.transpose() * flip;
        p.centre = -(world_to_camera.transpose() * t);
        poses.push_back(p);
    }
    return poses;
}

Similarity fit_similarity(const std::vector<Vector3d>& from, const std::vector<Vector3d>& to) {
    if (from.size() != to.size())
        throw Error("similarity fit: " + std::to_string(from.size()) + " points to map onto " +
                    std::to_string(to.size()));
    if (from.size() < 3)
        throw Error("similarity fit: needs at least 3 point pairs, got " + std::to_string(from.size()));
    auto s = detail::try_fit_similarity(from, to);
    if (!s)
        throw Error(
            "similarity fit: the points are coincident, collinear or not finite; the alignment is "
            "undetermined");
    return *s;
}

PoseComparison compare_poses(const std::vector<CameraPose>& estimate,
                             const std::vector<CameraPose>& reference) {
    if (estimate.size() != reference.size())
        throw Error("pose comparison: " + std::to_string(estimate.size()) + " estimated poses but " +
                    std::to_string(reference.size()) + " reference poses");
    std::vector<Vector3d> from, to;
    for (size_t i = 0; i < estimate.size(); ++i) {
        from.push_back(estimate[i].centre);
        to.push_back(reference[i].centre);
    }
    if (from.size() < 3)
        throw Error("pose comparison: needs at least 3 matched cameras, got " + std::to_string(from.size()));
    const auto sim = detail::try_fit_similarity(from, to);
    if (!sim)
        throw Error("pose comparison: the camera centres are coincident or on one line; cannot align them");
    PoseComparison out;
    out.count = estimate.size();
    out.similarity = *sim;
    out.trajectory_scale = detail::trajectory_scale(to);
    for (size_t i = 0; i < estimate.size(); ++i) {
        out.centre_errors.push_back((sim->apply(from[i]) - to[i]).norm());
        out.rotation_errors_deg.push_back(
            rotation_angle_deg(reference[i].rotation, sim->rotation * estimate[i].rotation));
    }
    out.centre = stats(out.centre_errors);
    out.rotation_deg = stats(out.rotation_errors_deg);
    return out;
}

MatchedPoses match_by_name(const std::vector<CameraPose>& estimate,
                           const std::vector<CameraPose>& reference) {
    auto index = [](const std::vector<CameraPose>& poses, const char* side) {
        std::map<std::string, size_t> by_name;
        for (size_t i = 0; i < poses.size(); ++i) {
            const std::string name = fs::path(poses[i].name).filename().string();
            if (!by_name.emplace(name, i).second)
                throw Error(std::string(side) + ": the name '" + name +
                            "' appears twice; cannot match by name");
        }
        return by_name;
    };
    const auto est = index(estimate, "estimate");
    index(reference, "reference");  // only for its duplicate check
    MatchedPoses m;
    for (const CameraPose& r : reference) {
        auto it = est.find(fs::path(r.name).filename().string());
        if (it == est.end()) {
            ++m.unmatched_reference;
            continue;
        }
        m.estimate.push_back(estimate[it->second]);
        m.reference.push_back(r);
    }
    m.unmatched_estimate = estimate.size() - m.estimate.size();
    return m;
}

MatchedPoses match_by_time(const std::vector<CameraPose>& estimate, const std::vector<double>& estimate_times,
                           const std::vector<CameraPose>& reference,
                           const std::vector<double>& reference_times) {
    if (estimate.size() != estimate_times.size() || reference.size() != reference_times.size())
        throw Error("time matching: each pose list needs one time per pose");
    const detail::TimedTrack track(estimate_times);
    MatchedPoses m;
    std::vector<bool> used(estimate.size(), false);
    for (size_t i = 0; i < reference.size(); ++i) {
        const auto at = track.locate(reference_times[i]);
        if (!at) {
            ++m.unmatched_reference;
            continue;
        }
        const CameraPose& p0 = estimate[at->i0];
        const CameraPose& p1 = estimate[at->i1];
        CameraPose p;
        p.name = p0.name;
        p.centre = (1 - at->u) * p0.centre + at->u * p1.centre;
        const Eigen::Quaterniond q0(p0.rotation), q1(p1.rotation);
        p.rotation = q0.slerp(at->u, q1).toRotationMatrix();
        m.estimate.push_back(p);
        m.reference.push_back(reference[i]);
        used[at->i0] = used[at->i1] = true;
    }
    m.unmatched_estimate = size_t(std::count(used.begin(), used.end(), false));
    return m;
}

}  // namespace npt::capture
