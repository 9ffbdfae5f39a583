// How far recovered camera poses are from a reference (ground truth or another reconstruction): poses from a
// transforms.json or a COLMAP model, matched by name or by time, a similarity alignment (Umeyama) of the
// camera centres, and per-camera centre and rotation errors. docs/formats.md, "Comparing poses".
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "capture/colmap_model.h"

namespace npt::capture {

// One camera: camera-to-world rotation with OpenGL camera axes (looks down -Z, +Y up) and its centre.
struct CameraPose {
    std::string name;
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
};

// p -> scale * rotation * p + translation.
struct Similarity {
    double scale = 1;
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    Eigen::Vector3d translation = Eigen::Vector3d::Zero();

    Eigen::Vector3d apply(const Eigen::Vector3d& p) const { return scale * (rotation * p) + translation; }
};

struct ErrorStats {
    double mean = 0, median = 0, max = 0;
};

struct PoseComparison {
    size_t count = 0;
    ErrorStats rotation_deg;  // angle between the aligned estimate's and the reference's camera rotations
    ErrorStats centre;  // distance of the aligned estimate's centre from the reference's, reference units
    // RMS distance of the reference centres from their mean: divide centre errors by it for relative errors.
    double trajectory_scale = 0;
    Similarity similarity;                                   // estimate world -> reference world
    std::vector<double> rotation_errors_deg, centre_errors;  // per camera, in input order
};

// Pairs of poses, index i of `estimate` belonging to index i of `reference`.
struct MatchedPoses {
    std::vector<CameraPose> estimate, reference;
    // By name: poses without a partner. By time: estimate poses that bracket no reference time, and reference
    // poses outside the estimate's time span.
    size_t unmatched_estimate = 0, unmatched_reference = 0;
};

// The frames of an instant-ngp transforms.json; name = file name of file_path ("frame_00012.png"). Throws
// npt::Error naming the file and the frame and field for a missing or malformed file, a transform_matrix that
// is not 4x4 finite numbers or whose 3x3 part is not a rotation, or no frame at all.
std::vector<CameraPose> read_transforms_poses(const std::filesystem::path& json);

// COLMAP's world-to-camera poses (OpenCV camera axes) as OpenGL camera-to-world ones; name = the image name.
std::vector<CameraPose> colmap_poses(const ColmapModel& model);

// Umeyama's least-squares similarity (rotation with det +1) taking `from` onto `to`. Throws npt::Error when
// the lists differ in length, hold fewer than 3 points, non-finite values, or points that are all coincident
// or on one line (the rotation about that line is then undetermined).
Similarity fit_similarity(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to);

// Aligns the estimate's centres to the reference's (fit_similarity), then measures every camera. The lists
// are already matched (same length, i <-> i); throws npt::Error otherwise or when the alignment is
// degenerate.
PoseComparison compare_poses(const std::vector<CameraPose>& estimate,
                             const std::vector<CameraPose>& reference);

// Pairs of equal file names (a folder part in a COLMAP image name is ignored), in the reference's order.
// Throws npt::Error when a name appears twice on one side.
MatchedPoses match_by_name(const std::vector<CameraPose>& estimate, const std::vector<CameraPose>& reference);

// For each reference pose, the estimate interpolated at its time between the two estimate poses that bracket
// it (centre linearly, rotation by slerp); reference poses outside the estimate's time span are skipped
// (counted in unmatched_reference). Times are any increasing unit (seconds, video frame numbers); the
// estimate may come in any order. Throws npt::Error when a list and its times differ in length, there are
// fewer than 2 estimate poses, or two share a time.
MatchedPoses match_by_time(const std::vector<CameraPose>& estimate, const std::vector<double>& estimate_times,
                           const std::vector<CameraPose>& reference,
                           const std::vector<double>& reference_times);

// Where reference frame i was taken: video frame a * i + b, a and b unknown (frames extracted at a constant
// rate, e.g. ffmpeg -vf fps=3 from a 30 fps video: a = 10).
struct TimeMappingSettings {
    double a_min = 0.5, a_max = 30;
    // Candidates that put fewer of the reference frames inside the estimate's frame span are not considered:
    // a few matched cameras always fit well, so the score alone would prefer them.
    double min_matched_fraction = 0.5;
};

struct TimeMapping {
    double a = 1, b = 0;
    MatchedPoses matched;
    PoseComparison comparison;
};

// Searches a (geometric steps of 1% over [a_min, a_max]) and b (steps of 1/200 of the estimate's frame span)
// for the mapping with the smallest median centre error relative to the trajectory scale after alignment,
// then refines around the best on two grids 10 and 100 times finer. Assumes both reconstructions come from
// one video, the reference's frames in index order at a constant rate, and a camera path without symmetry:
// along a perfectly regular orbit a shift in b is a rotation about the orbit's axis and cannot be told apart
// from the centres. One similarity must fit the whole overlap: a reconstruction made of pieces misplaced
// against each other (docs/benchmarks.md, the beer capture) scores badly at every mapping, and the winner
// means nothing. Throws npt::Error when no candidate matches min_matched_fraction of the reference with a
// sound alignment.
TimeMapping fit_time_mapping(const std::vector<CameraPose>& estimate,
                             const std::vector<double>& estimate_frames,
                             const std::vector<CameraPose>& reference,
                             const TimeMappingSettings& settings = {});

}  // namespace npt::capture
