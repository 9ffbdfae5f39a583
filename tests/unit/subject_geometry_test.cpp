#include "capture/subject/subject_geometry.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>

#include "core/error.h"

namespace npt::capture::subject {
namespace {

constexpr double k_pi = std::numbers::pi;

// A room like scripts/make_handheld_capture.py's, in metres with Z up: a table top at z = 0.75, an object (a
// cylinder of radius 0.06 and height 0.22 whose base centre is at (0.02, -0.01) on the table), props on the
// table 0.25..0.38 m away, the floor, walls, outliers; a hand-held walk around the object at 0.9 m. Then the
// whole scene is moved into "capture coordinates" by an arbitrary similarity (COLMAP's gauge): rotated, scaled
// by `units_per_metre` and shifted.
struct Truth {
    Vector3d up;           // capture coordinates
    Vector3d base_center;  // capture coordinates
    double height = 0;     // capture units
    double units_per_metre = 0;
};

struct SyntheticCapture {
    std::vector<Vector3d> points;
    std::vector<ViewRay> views;
    Truth truth;
    Eigen::Matrix3d rot;
    Vector3d shift;
    Vector3d to_metres(const Vector3d& p) const { return rot.transpose() * (p - shift) / truth.units_per_metre; }
};

SyntheticCapture make_capture(uint64_t seed, double units_per_metre, double outlier_fraction = 0.05,
                              double point_noise_m = 0.001, double object_top_seen = 1.0) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    std::normal_distribution<double> gauss(0.0, 1.0);
    const double top = 0.75, radius = 0.06, height = 0.22;
    const Vector3d base(0.02, -0.01, top);
    std::vector<Vector3d> pts;
    const auto noisy = [&](const Vector3d& p) {
        Vector3d q = p;
        for (int a = 0; a < 3; ++a) q[a] += point_noise_m * gauss(rng);
        return q;
    };
    for (int i = 0; i < 3000; ++i)  // table top 1.4 x 0.9, not under the object
        if (Vector3d p(-0.7 + 1.4 * uni(rng), -0.45 + 0.9 * uni(rng), top); std::hypot(p.x() - base.x(), p.y() - base.y()) > radius)
            pts.push_back(noisy(p));
    for (int i = 0; i < 1500; ++i)  // floor, seen beyond the table
        pts.push_back(noisy({-3.5 + 7 * uni(rng), -3.5 + 7 * uni(rng), 0.0}));
    for (int i = 0; i < 1500; ++i) {  // walls
        const double a = 2 * k_pi * uni(rng);
        pts.push_back(noisy({3.5 * std::cos(a), 3.5 * std::sin(a), 2.8 * uni(rng)}));
    }
    for (int i = 0; i < 800; ++i) {  // the object's side and top
        const double a = 2 * k_pi * uni(rng);
        if (i % 8 == 0 && object_top_seen >= 1.0) {
            const double r = radius * std::sqrt(uni(rng));
            pts.push_back(noisy(base + Vector3d(r * std::cos(a), r * std::sin(a), height)));
        } else {
            pts.push_back(noisy(base + Vector3d(radius * std::cos(a), radius * std::sin(a), object_top_seen * height * uni(rng))));
        }
    }
    for (int k = 0; k < 5; ++k) {  // props: boxes up to 8 cm high
        const double a = 2 * k_pi * (k + 0.3 * uni(rng)) / 5, r = 0.25 + 0.13 * uni(rng);
        const Vector3d c(r * std::cos(a), std::clamp(r * std::sin(a), -0.38, 0.38), top);
        const double hx = 0.03 + 0.04 * uni(rng), hy = 0.03 + 0.04 * uni(rng), hz = 0.02 + 0.06 * uni(rng);
        for (int i = 0; i < 250; ++i)
            pts.push_back(noisy(c + Vector3d((2 * uni(rng) - 1) * hx, (2 * uni(rng) - 1) * hy, hz * uni(rng))));
    }
    const size_t clean = pts.size();
    for (size_t i = 0; i < size_t(outlier_fraction * double(clean)); ++i)  // mismatches anywhere in the room
        pts.push_back({-3.5 + 7 * uni(rng), -3.5 + 7 * uni(rng), 2.8 * uni(rng)});

    std::vector<ViewRay> views;
    const Vector3d centre = base + Vector3d(0, 0, 0.12);
    for (int k = 0; k < 80; ++k) {
        const double a = 2 * k_pi * k / 80, r = 0.9 + 0.06 * std::sin(3 * a);
        const Vector3d eye(r * std::cos(a), r * std::sin(a), top + 0.35 + 0.05 * std::sin(2 * a + 1));
        const Vector3d target = centre + 0.03 * Vector3d(gauss(rng), gauss(rng), gauss(rng));
        ViewRay v;
        v.origin = eye;
        v.axis = (target - eye).normalized();
        const Vector3d right = v.axis.cross(Vector3d::UnitZ()).normalized();
        const double roll = 3 * k_pi / 180 * gauss(rng);
        const Vector3d up0 = right.cross(v.axis);
        v.up = (std::cos(roll) * up0 + std::sin(roll) * right).normalized();
        views.push_back(v);
    }

    // Into capture coordinates.
    const Eigen::Matrix3d rot =
        Eigen::AngleAxisd(0.7 + seed, Vector3d(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
    const Vector3d shift(0.4, -1.1, 2.0);
    const auto to_capture = [&](const Vector3d& p) -> Vector3d { return units_per_metre * (rot * p) + shift; };
    SyntheticCapture c;
    for (const Vector3d& p : pts) c.points.push_back(to_capture(p));
    for (ViewRay v : views) {
        v.origin = to_capture(v.origin);
        v.axis = rot * v.axis;
        v.up = rot * v.up;
        c.views.push_back(v);
    }
    c.truth = {rot * Vector3d::UnitZ(), to_capture(base), units_per_metre * height, units_per_metre};
    c.rot = rot;
    c.shift = shift;
    return c;
}

double angle_deg(const Vector3d& a, const Vector3d& b) {
    return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180 / k_pi;
}

TEST(SubjectGeometry, FixationPointOfAxesThroughOnePointIsThatPoint) {
    const Vector3d p(1, 2, 3);
    std::vector<ViewRay> views;
    for (int k = 0; k < 6; ++k) {
        const Vector3d o(4 * std::cos(k), 4 * std::sin(k), 1 + 0.3 * k);
        views.push_back({o, (p - o).normalized(), Vector3d::UnitZ()});
    }
    EXPECT_LT((fixation_point(views) - p).norm(), 1e-9);
}

TEST(SubjectGeometry, FixationPointIsTheLeastSquaresPointOfSkewAxes) {
    // Two perpendicular axes 2 apart (x axis at z = 0, y axis at z = 2): the closest point is halfway.
    const std::vector<ViewRay> views = {{Vector3d(-5, 0, 0), Vector3d::UnitX(), Vector3d::UnitZ()},
                                        {Vector3d(0, -5, 2), Vector3d::UnitY(), Vector3d::UnitZ()}};
    EXPECT_LT((fixation_point(views) - Vector3d(0, 0, 1)).norm(), 1e-9);
}

TEST(SubjectGeometry, ParallelAxesOrTooFewViewsAreErrors) {
    const ViewRay a{Vector3d(0, 0, 0), Vector3d::UnitX(), Vector3d::UnitZ()};
    const ViewRay b{Vector3d(0, 1, 0), Vector3d::UnitX(), Vector3d::UnitZ()};
    EXPECT_THROW(fixation_point({a}), Error);
    EXPECT_THROW(fixation_point({a, b}), Error);
}

// The targets: up within 2 degrees, the base plane within 1% of the object's height.
TEST(SubjectGeometry, FindsTheTableUpAndTheObjectInAnyGauge) {
    for (const auto& [seed, units] : {std::pair{1ull, 1.0}, std::pair{2ull, 4.4}, std::pair{3ull, 0.05}}) {
        SCOPED_TRACE(seed);
        const SyntheticCapture c = make_capture(seed, units);
        const SubjectGeometry g = find_subject(c.points, c.views);
        EXPECT_LT(angle_deg(g.up, c.truth.up), 0.5);
        // The plane's height at the true base centre, against the object's height.
        EXPECT_LT(std::abs(g.plane.height(c.truth.base_center)), 0.01 * c.truth.height);
        const Vector3d off = g.base_center - c.truth.base_center;
        EXPECT_LT((off - off.dot(g.up) * g.up).norm(), 0.01 * units);  // within 1 cm horizontally
        EXPECT_NEAR(g.height, c.truth.height, 0.06 * c.truth.height);
        // The box holds the object (radius 6 cm) and none of the props (>= 25 cm away, minus their size).
        for (const double a : {0.0, 0.5 * k_pi, k_pi, 1.5 * k_pi}) {
            const Vector3d side = g.to_object(c.truth.base_center) +
                                  Vector3d(0.06 * units * std::cos(a), 0.06 * units * std::sin(a), 0);
            EXPECT_GT(side.x(), g.box_min.x());
            EXPECT_LT(side.x(), g.box_max.x());
            EXPECT_GT(side.y(), g.box_min.y());
            EXPECT_LT(side.y(), g.box_max.y());
        }
        EXPECT_LT(g.box_max.x() - g.box_min.x(), 0.25 * units);
        EXPECT_LT(g.box_max.y() - g.box_min.y(), 0.25 * units);
        EXPECT_GT(g.box_max.z(), c.truth.height);
        EXPECT_DOUBLE_EQ(g.box_min.z(), 0.0);
        // The frame is right-handed and orthonormal, the base on the plane.
        EXPECT_NEAR(g.x_axis.cross(g.y_axis).dot(g.up), 1.0, 1e-12);
        EXPECT_NEAR(g.plane.height(g.base_center), 0.0, 1e-9 * units);
        EXPECT_LT((g.from_object(g.to_object(c.points[7])) - c.points[7]).norm(), 1e-9 * units);
    }
}

TEST(SubjectGeometry, ManyOutliersAndNoisierPointsStillGiveTheTable) {
    const SyntheticCapture c = make_capture(4, 2.0, /*outliers=*/0.4, /*noise=*/0.002);
    const SubjectGeometry g = find_subject(c.points, c.views);
    EXPECT_LT(angle_deg(g.up, c.truth.up), 1.0);
    EXPECT_LT(std::abs(g.plane.height(c.truth.base_center)), 0.01 * c.truth.height);
    EXPECT_NEAR(g.height, c.truth.height, 0.1 * c.truth.height);
}

TEST(SubjectGeometry, NoPointsOrNoPlaneAreErrorsNotGuesses) {
    SyntheticCapture c = make_capture(5, 1.0);
    EXPECT_THROW(find_subject({}, c.views), Error);
    // Only the object and points above the cameras: no plane has every camera on its upper side.
    std::vector<Vector3d> high;
    for (const Vector3d& p : c.points)
        if (c.truth.up.dot(p - c.truth.base_center) > 1.0 * c.truth.units_per_metre) high.push_back(p);
    EXPECT_THROW(find_subject(high, c.views), Error);
}

// Few sparse points on the object (only its lower 40%, as SIFT finds on a smooth top): the sparse box is too
// low; a dense field (the object, the props, the table under them all) gives the object's full height and
// width, without the props beside it or the table below.
TEST(SubjectGeometry, ADenseFieldGivesTheWholeObjectAndNotItsNeighbours) {
    const double units = 3.0;
    const SyntheticCapture c = make_capture(6, units, 0.05, 0.001, /*object_top_seen=*/0.4);
    const SubjectGeometry g = find_subject(c.points, c.views);
    EXPECT_LT(g.height, 0.5 * c.truth.height);  // the sparse estimate misses the top
    const Vector3d base(0.02, -0.01, 0.75);
    const auto opacity = [&](const Vector3d& p) {
        const Vector3d m = c.to_metres(p);
        if (m.z() < 0.75) return 1.0;  // the table slab (and everything under it)
        const Vector3d q = m - base;
        if (std::hypot(q.x(), q.y()) < 0.06 && q.z() < 0.22) return 1.0;  // the object
        if (std::hypot(m.x() - 0.3, m.y()) < 0.05 && q.z() < 0.1) return 1.0;  // a prop 30 cm away
        return 0.0;
    };
    // 8 mm cells: 0.9 M of them (4 mm took 100 s under ASan for 7 M); the bounds below hold for either.
    const DenseBox d = refine_box_with_field(g, 0.008 * units, opacity);
    ASSERT_TRUE(d.found);
    EXPECT_NEAR(d.geometry.height, c.truth.height, 0.03 * c.truth.height);
    // The box: the object's 12 cm diameter plus a cell or two each side, not the prop's 30 cm away.
    const double width = (d.geometry.box_max.x() - d.geometry.box_min.x()) / units;
    EXPECT_GT(width, 0.12);
    EXPECT_LT(width, 0.14);
    const Vector3d off = d.geometry.base_center - c.truth.base_center;
    EXPECT_LT((off - off.dot(g.up) * g.up).norm(), 0.005 * units);
    EXPECT_DOUBLE_EQ(d.geometry.box_min.z(), 0.0);
    // An empty field finds nothing and leaves the geometry as it was.
    const DenseBox none = refine_box_with_field(g, 0.008 * units, [](const Vector3d&) { return 0.0; });
    EXPECT_FALSE(none.found);
    EXPECT_EQ(none.geometry.height, g.height);
}

}  // namespace
}  // namespace npt::capture::subject
