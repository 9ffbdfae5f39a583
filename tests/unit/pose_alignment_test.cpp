// Pose comparison: Umeyama against similarities we made (exact and with noise), degenerate point sets,
// per-camera errors for a known perturbation, COLMAP's convention on a camera computed by hand, interpolation
// by time, the (a, b) frame-rate search on a synthetic path, and bad transforms.json files.
#include "capture/pose_alignment.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "capture/transforms_writer.h"
#include "core/error.h"
#include "test_support.h"

namespace npt::capture {
namespace {

namespace fs = std::filesystem;
using Eigen::AngleAxisd;
using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr double k_deg = M_PI / 180;

Matrix3d random_rotation(std::mt19937& rng) {
    std::normal_distribution<double> g;
    return Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
}

std::vector<Vector3d> random_points(std::mt19937& rng, size_t n) {
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<Vector3d> p;
    for (size_t i = 0; i < n; ++i) p.emplace_back(u(rng), u(rng), u(rng));
    return p;
}

double angle_deg(const Matrix3d& a, const Matrix3d& b) {
    return AngleAxisd(a.transpose() * b).angle() / k_deg;
}

// A camera looking at the origin from `centre`, +Y roughly world +z (OpenGL axes).
CameraPose look_at_origin(const Vector3d& centre, std::string name) {
    const Vector3d back = centre.normalized();  // camera +Z points away from what it looks at
    const Vector3d right = Vector3d(0, 0, 1).cross(back).normalized();
    CameraPose p;
    p.name = std::move(name);
    p.rotation.col(0) = right;
    p.rotation.col(1) = back.cross(right);
    p.rotation.col(2) = back;
    p.centre = centre;
    return p;
}

// The same camera in a world moved by s: rotation composed, centre mapped.
CameraPose transformed(const CameraPose& p, const Similarity& s) {
    CameraPose q = p;
    q.rotation = s.rotation * p.rotation;
    q.centre = s.apply(p.centre);
    return q;
}

Similarity some_similarity(std::mt19937& rng) {
    Similarity s;
    s.scale = 3.7;
    s.rotation = random_rotation(rng);
    s.translation = Vector3d(4, -2, 9);
    return s;
}

TEST(PoseAlignment, UmeyamaRecoversAnExactSimilarity) {
    std::mt19937 rng(1);
    for (int trial = 0; trial < 20; ++trial) {
        const Similarity truth{std::exp(std::uniform_real_distribution<double>(-3, 3)(rng)),
                               random_rotation(rng), Vector3d::Random() * 10};
        const auto from = random_points(rng, 3 + size_t(trial));
        std::vector<Vector3d> to;
        for (const auto& p : from) to.push_back(truth.apply(p));
        const Similarity fit = fit_similarity(from, to);
        // Double precision through a 3x3 SVD: errors of a few ulps of the largest number involved.
        EXPECT_NEAR(fit.scale / truth.scale, 1, 1e-10);
        EXPECT_LT((fit.rotation - truth.rotation).cwiseAbs().maxCoeff(), 1e-10);
        EXPECT_LT((fit.translation - truth.translation).norm(), 1e-9 * (1 + truth.translation.norm()));
        EXPECT_NEAR(fit.rotation.determinant(), 1, 1e-12);
    }
}

TEST(PoseAlignment, UmeyamaWithNoiseIsWithinItsStandardError) {
    std::mt19937 rng(2);
    const Similarity truth = some_similarity(rng);
    const size_t n = 2000;
    const double sigma = 0.05;  // per axis, in the target's units
    const auto from = random_points(rng, n);
    std::normal_distribution<double> noise(0, sigma);
    std::vector<Vector3d> to;
    for (const auto& p : from) to.push_back(truth.apply(p) + Vector3d(noise(rng), noise(rng), noise(rng)));
    const Similarity fit = fit_similarity(from, to);
    // Points spread with RMS radius 1 (uniform in [-1, 1]^3): scale and rotation (radians) have standard
    // errors about sigma / (s sqrt(n)), the translation sigma / sqrt(n) per axis. 5 standard errors.
    const double se = sigma / (truth.scale * std::sqrt(double(n)));
    EXPECT_NEAR(fit.scale / truth.scale, 1, 5 * se);
    EXPECT_LT(angle_deg(fit.rotation, truth.rotation) * k_deg, 5 * se * std::sqrt(3.0));
    EXPECT_LT((fit.translation - truth.translation).norm(),
              5 * std::sqrt(3.0) * sigma / std::sqrt(double(n)));
}

TEST(PoseAlignment, UmeyamaRefusesDegeneratePoints) {
    const std::vector<Vector3d> two{{0, 0, 0}, {1, 0, 0}};
    test::expect_error_message([&] { fit_similarity(two, two); }, {"at least 3", "got 2"});
    const std::vector<Vector3d> same(5, Vector3d(1, 2, 3));
    const std::vector<Vector3d> spread{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
    test::expect_error_message([&] { fit_similarity(same, spread); }, {"coincident"});
    test::expect_error_message([&] { fit_similarity(spread, same); }, {"coincident"});
    std::vector<Vector3d> line;
    for (int i = 0; i < 6; ++i) line.emplace_back(i, 2 * i, -i);
    const std::vector<Vector3d> spread6{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}, {2, 0, 1}};
    test::expect_error_message([&] { fit_similarity(line, line); }, {"collinear"});
    test::expect_error_message([&] { fit_similarity(spread6, line); }, {"collinear"});
    test::expect_error_message([&] { fit_similarity(spread, spread6); }, {"5 points", "6"});
    std::vector<Vector3d> nan = spread;
    nan[2].x() = NAN;
    test::expect_error_message([&] { fit_similarity(nan, spread); }, {"not finite"});
}

std::vector<CameraPose> ring(size_t n) {
    std::vector<CameraPose> poses;
    for (size_t i = 0; i < n; ++i) {
        const double t = 2 * M_PI * double(i) / double(n);
        poses.push_back(look_at_origin({3 * std::cos(t), 3 * std::sin(t), 0.5 + 0.3 * std::sin(2 * t)},
                                       "frame_" + std::to_string(i) + ".png"));
    }
    return poses;
}

TEST(PoseAlignment, CompareGivesZeroForASimilarCopyAndTheRotationOfAPerturbedCamera) {
    std::mt19937 rng(3);
    const auto reference = ring(24);
    const Similarity s = some_similarity(rng);
    std::vector<CameraPose> estimate;
    for (const auto& p : reference) estimate.push_back(transformed(p, s));
    PoseComparison c = compare_poses(estimate, reference);
    EXPECT_EQ(c.count, 24u);
    EXPECT_LT(c.centre.max, 1e-10);  // rounding of numbers ~10
    EXPECT_LT(c.rotation_deg.max, 1e-6);
    EXPECT_NEAR(c.similarity.scale * s.scale, 1, 1e-12);
    double rms = 0;  // ring radius 3 around the mean (0, 0, 0.5), heights 0.3 sin(2t) around it
    for (const auto& p : reference) rms += (p.centre - Vector3d(0, 0, 0.5)).squaredNorm();
    EXPECT_NEAR(c.trajectory_scale, std::sqrt(rms / 24), 1e-12);

    // One camera turned 2 degrees about its own axis: centres untouched, so the alignment is unchanged.
    estimate[5].rotation = estimate[5].rotation * AngleAxisd(2 * k_deg, Vector3d(0.3, -1, 0.2).normalized());
    c = compare_poses(estimate, reference);
    EXPECT_NEAR(c.rotation_errors_deg[5], 2, 1e-9);
    EXPECT_NEAR(c.rotation_deg.max, 2, 1e-9);
    EXPECT_NEAR(c.rotation_deg.mean, 2.0 / 24, 1e-9);
    EXPECT_LT(c.rotation_deg.median, 1e-6);
    EXPECT_LT(c.centre.max, 1e-10);

    test::expect_error_message([&] { compare_poses(estimate, ring(5)); }, {"24", "5"});
}

TEST(PoseAlignment, ColmapPosesAreOpenGLCameraToWorld) {
    ColmapModel model;
    ColmapImage a;
    a.name = "a.png";
    a.tvec = {1, 2, 3};  // identity rotation: camera axes = world axes (OpenCV), centre -t
    model.images.push_back(a);
    ColmapImage b;
    b.name = "b.png";
    // World to camera: 90 degrees about z, R = [[0,-1,0],[1,0,0],[0,0,1]]; t = (0, 0, 5).
    b.qvec = {std::cos(M_PI / 4), 0, 0, std::sin(M_PI / 4)};
    b.tvec = {0, 0, 5};
    model.images.push_back(b);
    const auto poses = colmap_poses(model);
    ASSERT_EQ(poses.size(), 2u);
    EXPECT_EQ(poses[0].name, "a.png");
    EXPECT_LT((poses[0].centre - Vector3d(-1, -2, -3)).norm(), 1e-12);
    EXPECT_LT((poses[0].rotation - Matrix3d(Vector3d(1, -1, -1).asDiagonal())).norm(), 1e-12);
    // By hand: R^T = [[0,1,0],[-1,0,0],[0,0,1]]; centre -R^T t = (0, 0, -5); OpenCV x, -y, -z through R^T
    // give the OpenGL columns (0,-1,0), (-1,0,0), (0,0,-1): the camera looks down world +z, at the origin.
    Matrix3d expected;
    expected << 0, -1, 0, -1, 0, 0, 0, 0, -1;
    EXPECT_LT((poses[1].centre - Vector3d(0, 0, -5)).norm(), 1e-12);
    EXPECT_LT((poses[1].rotation - expected).norm(), 1e-12);
}

// write_transforms normalises COLMAP's world by a similarity, so its file and colmap_poses of the same model
// must agree exactly after alignment: the two readers share the camera convention.
TEST(PoseAlignment, TransformsWrittenFromAModelMatchItsColmapPoses) {
    ColmapModel model;
    ColmapCamera cam;
    cam.id = 1;
    cam.model = CameraModel::pinhole;
    cam.width = 64;
    cam.height = 48;
    cam.params = {50, 50, 32, 24};
    model.cameras.push_back(cam);
    const Matrix3d flip = Vector3d(1, -1, -1).asDiagonal();
    const auto cameras = ring(12);
    for (size_t i = 0; i < cameras.size(); ++i) {
        ColmapImage im;
        im.id = int32_t(i + 1);
        im.camera_id = 1;
        im.name = cameras[i].name;
        const Matrix3d world_to_camera = (cameras[i].rotation * flip).transpose();
        const Eigen::Quaterniond q(world_to_camera);
        im.qvec = {q.w(), q.x(), q.y(), q.z()};
        const Vector3d t = -(world_to_camera * cameras[i].centre);
        im.tvec = {t.x(), t.y(), t.z()};
        model.images.push_back(im);
    }
    const auto from_model = colmap_poses(model);
    for (size_t i = 0; i < cameras.size(); ++i) {
        EXPECT_LT((from_model[i].centre - cameras[i].centre).norm(), 1e-12);
        EXPECT_LT(angle_deg(from_model[i].rotation, cameras[i].rotation), 1e-6);
    }
    const fs::path json = test::temp_dir() / "transforms.json";
    write_transforms(model, json);
    const MatchedPoses m = match_by_name(read_transforms_poses(json), from_model);
    ASSERT_EQ(m.estimate.size(), cameras.size());
    const PoseComparison c = compare_poses(m.estimate, m.reference);
    EXPECT_LT(c.centre.max, 1e-9);  // the file holds numbers printed with 17 digits or fewer
    EXPECT_LT(c.rotation_deg.max, 1e-6);
}

TEST(PoseAlignment, MatchByNamePairsFileNames) {
    auto est = ring(4);
    auto ref = ring(4);
    ref.erase(ref.begin());
    ref[0].name = "images/" + ref[0].name;  // a COLMAP name with a folder
    est.push_back(look_at_origin({1, 1, 1}, "extra.png"));
    const MatchedPoses m = match_by_name(est, ref);
    ASSERT_EQ(m.estimate.size(), 3u);
    EXPECT_EQ(m.estimate[0].name, "frame_1.png");
    EXPECT_EQ(m.reference[0].name, "images/frame_1.png");
    EXPECT_EQ(m.unmatched_estimate, 2u);
    EXPECT_EQ(m.unmatched_reference, 0u);
    est[1].name = est[0].name;
    test::expect_error_message([&] { match_by_name(est, ref); }, {"estimate", "frame_0.png", "twice"});
}

TEST(PoseAlignment, MatchByTimeInterpolatesBetweenBracketingFrames) {
    CameraPose p0, p1;
    p0.name = "p0";
    p1.name = "p1";
    p1.centre = Vector3d(2, 4, 6);
    p1.rotation = AngleAxisd(90 * k_deg, Vector3d::UnitZ()).toRotationMatrix();
    const std::vector<CameraPose> ref(4, CameraPose{});
    // Estimate given out of time order: it is sorted inside.
    const MatchedPoses m = match_by_time({p1, p0}, {2, 0}, ref, {-1, 1, 2, 3});
    ASSERT_EQ(m.estimate.size(), 2u);
    EXPECT_EQ(m.unmatched_reference, 2u);
    EXPECT_LT((m.estimate[0].centre - Vector3d(1, 2, 3)).norm(), 1e-12);
    EXPECT_NEAR(
        angle_deg(m.estimate[0].rotation, AngleAxisd(45 * k_deg, Vector3d::UnitZ()).toRotationMatrix()), 0,
        1e-9);
    EXPECT_LT((m.estimate[1].centre - p1.centre).norm(), 1e-12);
    EXPECT_NEAR(angle_deg(m.estimate[1].rotation, p1.rotation), 0, 1e-9);
    test::expect_error_message(
        [&] {
            match_by_time({p0, p1}, {1, 1}, ref, {0, 0, 0, 0});
        },
        {"two", "time 1"});
    test::expect_error_message(
        [&] {
            match_by_time({p0, p1}, {1}, ref, {0, 0, 0, 0});
        },
        {"one time per pose"});
}

// A camera path that no similarity maps onto a time-shifted copy of itself (a helix with a periodic radius
// would be one: shifting it by the radius's period is a screw motion): 1.3 turns, the radius growing and the
// height rising quadratically.
CameraPose path_at(double frame) {
    const double t = frame / 600;
    const double angle = 2 * M_PI * 1.3 * t;
    const double r = 2.5 + 1.2 * t + 0.3 * std::sin(5 * t);
    return look_at_origin({r * std::cos(angle), r * std::sin(angle), 0.2 + 1.5 * t * t}, "");
}

// The estimate: every 3rd video frame 0..600, named by frame number; the reference: frame a i + b in another
// world (a similarity away), as far as the video goes.
void expect_mapping_found(double a, double b) {
    std::mt19937 rng(4);
    std::vector<CameraPose> estimate;
    std::vector<double> frames;
    for (int f = 0; f <= 600; f += 3) {
        estimate.push_back(path_at(f));
        frames.push_back(f);
    }
    const Similarity s = some_similarity(rng);
    std::vector<CameraPose> reference;
    for (int i = 0; a * i + b <= 600; ++i) reference.push_back(transformed(path_at(a * i + b), s));
    const TimeMapping m = fit_time_mapping(estimate, frames, reference);
    // The search's last grid has steps of 0.01% in a and 1/20000 of the span in b. At the true (a, b) the
    // score is the error of interpolating linearly between frames 3 apart, ~1e-4 of the trajectory scale; a
    // shift of one frame costs ~4e-4 more (measured), so the best lies within half a frame of the truth.
    EXPECT_NEAR(m.a, a, 0.002 * a);
    EXPECT_NEAR(m.b, b, 0.5);
    // The last reference frame sits on the estimate's last frame: a b a hair above the truth puts it outside.
    EXPECT_GE(m.comparison.count, reference.size() - 1);
    EXPECT_LT(m.comparison.centre.median / m.comparison.trajectory_scale, 1e-3);
    EXPECT_LT(m.comparison.rotation_deg.max, 0.5);
}

TEST(PoseAlignment, FitTimeMappingFindsRate10Offset0) { expect_mapping_found(10, 0); }
TEST(PoseAlignment, FitTimeMappingFindsRate7Offset3) { expect_mapping_found(7, 3); }

TEST(PoseAlignment, ReadsTransformsPoses) {
    const fs::path dir = test::temp_dir();
    test::write_file(dir / "t.json", R"({"frames": [{"file_path": "./images/frame_00012.png",
        "transform_matrix": [[0, -1, 0, 1], [1, 0, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1]]}]})");
    const auto poses = read_transforms_poses(dir / "t.json");
    ASSERT_EQ(poses.size(), 1u);
    EXPECT_EQ(poses[0].name, "frame_00012.png");
    EXPECT_EQ(poses[0].centre, Vector3d(1, 2, 3));
    EXPECT_EQ(poses[0].rotation(0, 1), -1);
    EXPECT_EQ(poses[0].rotation(1, 0), 1);
}

TEST(PoseAlignment, BadTransformsJsonNamesFileAndField) {
    const fs::path dir = test::temp_dir();
    const std::string f = (dir / "t.json").string();
    test::expect_error_message([&] { read_transforms_poses(dir / "missing.json"); },
                               {"missing.json", "no such"});
    auto expect = [&](const std::string& content, std::initializer_list<std::string> parts) {
        test::write_file(f, content);
        test::expect_error_message([&] { read_transforms_poses(f); }, {f});
        test::expect_error_message([&] { read_transforms_poses(f); }, parts);
    };
    const std::string id = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
    expect("", {"file is empty"});
    expect("{", {"not valid JSON"});
    expect("[1, 2]", {"'frames'"});
    expect(R"({"frames": {}})", {"'frames'", "not an array"});
    expect(R"({"frames": []})", {"'frames' is empty"});
    expect(R"({"frames": [{"transform_matrix": )" + id + "}]}", {"frame 0", "'file_path'"});
    expect(
        R"({"frames": [{"file_path": "a.png", "transform_matrix": )" + id + R"(}, {"file_path": "b.png"}]})",
        {"frame 1 ('b.png')", "missing 'transform_matrix'"});
    expect(R"({"frames": [{"file_path": "a.png", "transform_matrix": [[1,0,0],[0,1,0],[0,0,1]]}]})",
           {"frame 0 ('a.png')", "4x4"});
    expect(
        R"({"frames": [{"file_path": "a.png", "transform_matrix": [[1,0,0,0],[0,1,0,"x"],[0,0,1,0],[0,0,0,1]]}]})",
        {"'a.png'", "4x4"});
    expect(
        R"({"frames": [{"file_path": "a.png", "transform_matrix": [[1,0,0,0],[0,1,0,null],[0,0,1,0],[0,0,0,1]]}]})",
        {"'a.png'", "null", "row 1"});
    expect(
        R"({"frames": [{"file_path": "a.png", "transform_matrix": [[2,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})",
        {"'a.png'", "not a rotation"});
}

}  // namespace
}  // namespace npt::capture
