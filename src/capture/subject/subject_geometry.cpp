// Fixation point, supporting plane and first box: least squares, RANSAC, a flood fill over a voxel hash and
// percentiles. Every threshold is a fraction of the capture's own scale (the cameras' distance from the
// fixation point), so the same settings hold for COLMAP's arbitrary units and for metres.
#include "capture/subject/subject_geometry.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <unordered_map>

#include "core/error.h"

namespace npt::capture::subject {

namespace {

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    const size_t mid = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + long(mid), v.end());
    return v[mid];
}

// The p-th percentile (0..100) by nearest rank on a sorted copy.
double percentile(std::vector<double> v, double p) {
    std::sort(v.begin(), v.end());
    const double rank = std::clamp(p / 100.0, 0.0, 1.0) * double(v.size() - 1);
    return v[size_t(std::lround(rank))];
}

Vector3d mean_up(const std::vector<ViewRay>& views) {
    Vector3d up = Vector3d::Zero();
    for (const ViewRay& v : views) up += v.up.normalized();
    if (up.norm() < 1e-6 * double(views.size()))
        throw Error("the cameras' image up directions cancel out: the capture has no common up");
    return up.normalized();
}

// Least-squares plane through points (centroid and the direction of least spread), normal towards `side`.
Plane fit_plane(const std::vector<Vector3d>& pts, const Vector3d& side) {
    Vector3d c = Vector3d::Zero();
    for (const Vector3d& p : pts) c += p;
    c /= double(pts.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const Vector3d& p : pts) cov += (p - c) * (p - c).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    Vector3d n = eig.eigenvectors().col(0).normalized();  // eigenvalues ascending
    if (n.dot(side) < 0) n = -n;
    return {n, -n.dot(c)};
}

struct CellKey {
    int64_t x, y, z;
    bool operator==(const CellKey&) const = default;
};
struct CellHash {
    size_t operator()(const CellKey& k) const {
        return size_t(k.x * 73856093 ^ k.y * 19349663 ^ k.z * 83492791);
    }
};

}  // namespace

Vector3d fixation_point(const std::vector<ViewRay>& views) {
    if (views.size() < 2) throw Error("the fixation point needs at least 2 cameras, got " + std::to_string(views.size()));
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Vector3d b = Vector3d::Zero();
    for (const ViewRay& v : views) {
        const Vector3d d = v.axis.normalized();
        const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - d * d.transpose();  // projects off the axis
        a += p;
        b += p * v.origin;
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(a);
    if (!(eig.eigenvalues()(0) > 1e-6 * eig.eigenvalues()(2)))
        throw Error("the cameras' optical axes are (nearly) parallel: they fixate no point");
    return a.ldlt().solve(b);
}

Plane fit_support_plane(const std::vector<Vector3d>& points, const std::vector<ViewRay>& views,
                        const Vector3d& fixation, double scale, const SubjectSettings& s, size_t* inliers_out,
                        size_t* candidates_out) {
    const Vector3d up = mean_up(views);
    const auto horizontal = [&](const Vector3d& p) {
        const Vector3d q = p - fixation;
        return (q - up.dot(q) * up).norm();
    };
    std::vector<double> ring;
    for (const ViewRay& v : views) ring.push_back(horizontal(v.origin));
    const double ring_radius = median(ring);
    // Only points inside the cameras' ring can be the top the object stands on; the floor and the walls
    // beyond the table are seen there too, but far less densely.
    std::vector<Vector3d> cand;
    for (const Vector3d& p : points)
        if (horizontal(p) < ring_radius) cand.push_back(p);
    if (candidates_out) *candidates_out = cand.size();
    if (cand.size() < 3)
        throw Error(fmt::format("only {} of the {} sparse points lie inside the cameras' ring: no surface to stand "
                                "the object on",
                                cand.size(), points.size()));
    const double t = s.inlier_fraction * scale;
    const double cos_tilt = std::cos(s.max_tilt_deg * std::numbers::pi / 180.0);
    const auto admissible = [&](const Plane& pl) {
        if (pl.normal.dot(up) < cos_tilt) return false;
        if (pl.height(fixation) <= t) return false;
        for (const ViewRay& v : views)
            if (pl.height(v.origin) <= t) return false;
        return true;
    };
    std::mt19937_64 rng(s.seed);
    std::uniform_int_distribution<size_t> pick(0, cand.size() - 1);
    Plane best;
    size_t best_count = 0;
    for (int it = 0; it < s.ransac_iterations; ++it) {
        const Vector3d &a = cand[pick(rng)], &b = cand[pick(rng)], &c = cand[pick(rng)];
        Vector3d n = (b - a).cross(c - a);
        const double len = n.norm();
        if (!(len > 1e-12 * scale * scale)) continue;
        n /= len;
        if (n.dot(up) < 0) n = -n;
        const Plane pl{n, -n.dot(a)};
        if (!admissible(pl)) continue;
        size_t count = 0;
        for (const Vector3d& p : cand) count += std::abs(pl.height(p)) < t;
        if (count > best_count) {
            best_count = count;
            best = pl;
        }
    }
    if (best_count < 3)
        throw Error(fmt::format("no supporting plane found: no plane within {:.0f} degrees of the cameras' up, below "
                                "them and the point they look at, holds 3 of the {} sparse points inside their ring",
                                s.max_tilt_deg, cand.size()));
    // Least squares on the inliers, with a shrinking band: the RANSAC plane is only as good as 3 points.
    Plane plane = best;
    size_t count = best_count;
    for (const double band : {t, t / 2, t / 3}) {
        std::vector<Vector3d> in;
        for (const Vector3d& p : cand)
            if (std::abs(plane.height(p)) < band) in.push_back(p);
        if (in.size() < 3) break;
        const Plane refined = fit_plane(in, up);
        if (!admissible(refined)) break;
        plane = refined;
        count = in.size();
    }
    if (inliers_out) *inliers_out = count;
    return plane;
}

SubjectGeometry find_subject(const std::vector<Vector3d>& points, const std::vector<ViewRay>& views,
                             const SubjectSettings& s) {
    SubjectGeometry g;
    g.fixation = fixation_point(views);
    std::vector<double> dist;
    for (const ViewRay& v : views) dist.push_back((v.origin - g.fixation).norm());
    g.scale = median(dist);
    if (!(g.scale > 0)) throw Error("the cameras all sit at the point they look at");
    g.plane = fit_support_plane(points, views, g.fixation, g.scale, s, &g.plane_inliers, &g.plane_candidates);
    g.up = g.plane.normal;
    Vector3d x = Vector3d::UnitX() - g.up.x() * g.up;
    if (x.norm() < 0.3) x = Vector3d::UnitY() - g.up.y() * g.up;
    g.x_axis = x.normalized();
    g.y_axis = g.up.cross(g.x_axis);
    const Vector3d foot = g.fixation - g.plane.height(g.fixation) * g.up;  // the fixation point on the plane

    // Seed points: above the plane, inside the cameras' ring, below their heights' reach.
    std::vector<double> ring, cam_height;
    for (const ViewRay& v : views) {
        const Vector3d q = v.origin - foot;
        ring.push_back((q - g.up.dot(q) * g.up).norm());
        cam_height.push_back(g.plane.height(v.origin));
    }
    const double ring_radius = median(ring), top_reach = 1.5 * std::max(median(cam_height), 0.0);
    g.ring_radius = ring_radius;
    g.top_reach = top_reach;
    struct Local {
        double u, v, h, r;
    };
    std::vector<Local> above;
    for (const Vector3d& p : points) {
        const Vector3d q = p - foot;
        const double h = g.plane.height(p), u = g.x_axis.dot(q), v = g.y_axis.dot(q);
        const double r = std::hypot(u, v);
        if (h > s.clearance_fraction * g.scale && h < top_reach && r < 0.6 * ring_radius) above.push_back({u, v, h, r});
    }
    if (above.empty())
        throw Error(fmt::format("no sparse point stands above the supporting plane near the point the cameras look "
                                "at ({} points, {} on the plane)",
                                points.size(), g.plane_inliers));
    // Flood fill from the points nearest the vertical through the fixation point, in hops of at most `link`.
    const double link = s.link_fraction * g.scale;
    std::unordered_map<CellKey, std::vector<size_t>, CellHash> cells;
    const auto key = [&](const Local& l) {
        return CellKey{int64_t(std::floor(l.u / link)), int64_t(std::floor(l.v / link)), int64_t(std::floor(l.h / link))};
    };
    for (size_t i = 0; i < above.size(); ++i) cells[key(above[i])].push_back(i);
    std::vector<int> component(above.size(), -1);
    int components = 0;
    const auto flood = [&](size_t start) {
        const int id = components++;
        std::vector<size_t> stack{start};
        component[start] = id;
        while (!stack.empty()) {
            const size_t i = stack.back();
            stack.pop_back();
            const CellKey k = key(above[i]);
            for (int64_t dx = -1; dx <= 1; ++dx)
                for (int64_t dy = -1; dy <= 1; ++dy)
                    for (int64_t dz = -1; dz <= 1; ++dz) {
                        const auto it = cells.find({k.x + dx, k.y + dy, k.z + dz});
                        if (it == cells.end()) continue;
                        for (const size_t j : it->second) {
                            if (component[j] >= 0) continue;
                            const double du = above[j].u - above[i].u, dv = above[j].v - above[i].v,
                                         dh = above[j].h - above[i].h;
                            if (du * du + dv * dv + dh * dh > link * link) continue;
                            component[j] = id;
                            stack.push_back(j);
                        }
                    }
        }
    };
    std::vector<size_t> order(above.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    const size_t k_nearest = std::min<size_t>(20, order.size());
    std::partial_sort(order.begin(), order.begin() + long(k_nearest), order.end(),
                      [&](size_t a, size_t b) { return above[a].r < above[b].r; });
    std::vector<int> votes;
    for (size_t n = 0; n < k_nearest; ++n) {
        if (component[order[n]] < 0) flood(order[n]);
        votes.resize(size_t(components), 0);
        ++votes[size_t(component[order[n]])];
    }
    const int chosen = int(std::max_element(votes.begin(), votes.end()) - votes.begin());
    std::vector<double> us, vs, hs;
    for (size_t i = 0; i < above.size(); ++i)
        if (component[i] == chosen) {
            us.push_back(above[i].u);
            vs.push_back(above[i].v);
            hs.push_back(above[i].h);
        }
    g.seed_points = us.size();
    const double u0 = percentile(us, s.low_percentile), u1 = percentile(us, s.high_percentile);
    const double v0 = percentile(vs, s.low_percentile), v1 = percentile(vs, s.high_percentile);
    g.height = percentile(hs, s.high_percentile);
    const double uc = 0.5 * (u0 + u1), vc = 0.5 * (v0 + v1);
    g.base_center = foot + uc * g.x_axis + vc * g.y_axis;
    const double margin = s.margin_fraction * std::max({u1 - u0, v1 - v0, g.height});
    g.box_min = Vector3d(u0 - uc - margin, v0 - vc - margin, 0.0);
    g.box_max = Vector3d(u1 - uc + margin, v1 - vc + margin, g.height + margin);
    return g;
}

DenseBox refine_box_with_field(const SubjectGeometry& g, double cell,
                               const std::function<double(const Vector3d&)>& opacity, const DenseBoxSettings& s) {
    DenseBox out;
    out.geometry = g;
    const double reach = 0.6 * g.ring_radius, z0 = s.clearance_fraction * g.scale, z1 = g.top_reach;
    if (!(cell > 0) || !(reach > 0) || !(z1 > z0)) return out;
    // The search box in the object frame, centred on the sparse box's vertical (the base centre).
    const auto count = [&](double c) {
        return size_t(std::ceil(2 * reach / c)) * size_t(std::ceil(2 * reach / c)) * size_t(std::ceil((z1 - z0) / c));
    };
    while (count(cell) > s.max_cells) cell *= 1.26;
    const int nx = int(std::ceil(2 * reach / cell)), nz = int(std::ceil((z1 - z0) / cell));
    const auto centre = [&](int i, int j, int k) {
        return Vector3d(-reach + (i + 0.5) * cell, -reach + (j + 0.5) * cell, z0 + (k + 0.5) * cell);
    };
    const auto idx = [&](int i, int j, int k) { return (size_t(k) * size_t(nx) + size_t(j)) * size_t(nx) + size_t(i); };
    std::vector<uint8_t> state(size_t(nx) * size_t(nx) * size_t(nz), 0);  // 1 occupied, 2 in the component
    std::vector<std::array<int, 3>> stack;
    for (int k = 0; k < nz; ++k)
        for (int j = 0; j < nx; ++j)
            for (int i = 0; i < nx; ++i) {
                const Vector3d o = centre(i, j, k);
                if (std::hypot(o.x(), o.y()) > reach) continue;
                if (opacity(g.from_object(o)) < s.threshold) continue;
                state[idx(i, j, k)] = 1;
                const bool in_sparse_box = o.x() > g.box_min.x() && o.x() < g.box_max.x() && o.y() > g.box_min.y() &&
                                           o.y() < g.box_max.y() && o.z() < g.box_max.z();
                if (in_sparse_box) {
                    state[idx(i, j, k)] = 2;
                    stack.push_back({i, j, k});
                }
            }
    if (stack.empty()) return out;
    Vector3d lo = Vector3d::Constant(INFINITY), hi = Vector3d::Constant(-INFINITY);
    while (!stack.empty()) {
        const auto [i, j, k] = stack.back();
        stack.pop_back();
        ++out.cells;
        const Vector3d o = centre(i, j, k);
        lo = lo.cwiseMin(o);
        hi = hi.cwiseMax(o);
        for (int dk = -1; dk <= 1; ++dk)
            for (int dj = -1; dj <= 1; ++dj)
                for (int di = -1; di <= 1; ++di) {
                    const int a = i + di, b = j + dj, c = k + dk;
                    if (a < 0 || b < 0 || c < 0 || a >= nx || b >= nx || c >= nz) continue;
                    uint8_t& st = state[idx(a, b, c)];
                    if (st != 1) continue;
                    st = 2;
                    stack.push_back({a, b, c});
                }
    }
    out.found = true;
    out.cell = cell;
    SubjectGeometry& r = out.geometry;
    // Cell centres -> the cells' faces, plus one cell of margin.
    const double pad = 1.5 * cell;
    const double uc = 0.5 * (lo.x() + hi.x()), vc = 0.5 * (lo.y() + hi.y());
    r.base_center = g.from_object(Vector3d(uc, vc, 0));
    // The object's top lies somewhere in its topmost occupied cell, whose opacity is its densest sample's: the
    // cell's centre is the unbiased guess, its top face half a cell high on average (the height sets the
    // metric scale with --height).
    r.height = hi.z();
    r.box_min = Vector3d(lo.x() - uc - pad, lo.y() - vc - pad, 0.0);
    r.box_max = Vector3d(hi.x() - uc + pad, hi.y() - vc + pad, hi.z() + pad);
    return out;
}

}  // namespace npt::capture::subject
