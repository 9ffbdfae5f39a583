// The colmap2nerf.py normalisation, written from its description in docs/formats.md: same steps, same
// constants, so a model converted here and by instant-ngp's script trains the same way.
#include "capture/transforms_writer.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/temp_file.h"

namespace npt::capture {
namespace {

namespace fs = std::filesystem;
using M3 = std::array<Vec3d, 3>;  // row-major 3x3

Vec3d sub(const Vec3d& a, const Vec3d& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3d add(const Vec3d& a, const Vec3d& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec3d mul(const Vec3d& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(const Vec3d& a, const Vec3d& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3d cross(const Vec3d& a, const Vec3d& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double length(const Vec3d& a) { return std::sqrt(dot(a, a)); }
Vec3d normalize(const Vec3d& a) { return mul(a, 1.0 / length(a)); }

M3 matmul(const M3& a, const M3& b) {
    M3 r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k)
                r[size_t(i)][size_t(j)] += a[size_t(i)][size_t(k)] * b[size_t(k)][size_t(j)];
    return r;
}
Vec3d mat_vec(const M3& a, const Vec3d& v) { return {dot(a[0], v), dot(a[1], v), dot(a[2], v)}; }

// The rotation taking direction a to direction b about their common normal (Rodrigues). Opposite directions
// have no unique such axis; any half turn about an axis normal to b works, and a fixed one keeps the result
// reproducible (colmap2nerf perturbs a at random instead).
M3 rotation_between(const Vec3d& a_in, const Vec3d& b_in) {
    const Vec3d a = normalize(a_in), b = normalize(b_in);
    const Vec3d v = cross(a, b);
    const double c = dot(a, b);
    if (c < -1 + 1e-10) {
        const Vec3d axis =
            normalize(std::abs(b[0]) < 0.9 ? cross(b, Vec3d{1, 0, 0}) : cross(b, Vec3d{0, 1, 0}));
        M3 r{};  // 2 axis axis^T - I
        for (size_t i = 0; i < 3; ++i)
            for (size_t j = 0; j < 3; ++j) r[i][j] = 2 * axis[i] * axis[j] - (i == j ? 1 : 0);
        return r;
    }
    const M3 k{{{0, -v[2], v[1]}, {v[2], 0, -v[0]}, {-v[1], v[0], 0}}};
    const M3 k2 = matmul(k, k);
    const double f = 1.0 / (1.0 + c);  // (1 - c) / s^2 with s^2 = 1 - c^2
    M3 r{};
    for (size_t i = 0; i < 3; ++i)
        for (size_t j = 0; j < 3; ++j) r[i][j] = (i == j ? 1 : 0) + k[i][j] + k2[i][j] * f;
    return r;
}

// The point nearest to both lines o + t d (t <= 0: the part in front of an OpenGL camera whose +Z is d), and
// a weight |da x db|^2 that vanishes for parallel lines, whose nearest point says nothing.
std::pair<Vec3d, double> closest_point_of_two_lines(const Vec3d& oa, Vec3d da, const Vec3d& ob, Vec3d db) {
    da = normalize(da);
    db = normalize(db);
    const Vec3d c = cross(da, db);
    const double denom = dot(c, c);
    const Vec3d t = sub(ob, oa);
    // det([t; d; c]) = t . (d x c)
    double ta = dot(t, cross(db, c)) / (denom + 1e-10);
    double tb = dot(t, cross(da, c)) / (denom + 1e-10);
    ta = std::min(ta, 0.0);
    tb = std::min(tb, 0.0);
    return {mul(add(add(oa, mul(da, ta)), add(ob, mul(db, tb))), 0.5), denom};
}

struct RigidFrame {
    M3 r;
    Vec3d t;
};

}  // namespace

NerfPoses nerf_poses(const ColmapModel& model, const TransformsSettings& settings) {
    if (model.images.empty()) throw Error("COLMAP model: no registered image to write a transforms.json for");
    std::vector<const ColmapImage*> images;
    for (const auto& im : model.images) images.push_back(&im);
    std::sort(images.begin(), images.end(), [](auto* a, auto* b) { return a->name < b->name; });

    // COLMAP's world as colmap2nerf turns it before levelling: x and y swapped, z negated (a proper
    // rotation). Levelling alone would do; keeping the step keeps our output colmap2nerf's up to rounding.
    const M3 world_swap{{{0, 1, 0}, {1, 0, 0}, {0, 0, -1}}};
    std::vector<RigidFrame> frames;
    Vec3d up{0, 0, 0};
    for (const ColmapImage* im : images) {
        const Mat4 c2w = im->camera_to_world();
        RigidFrame f;
        for (size_t r = 0; r < 3; ++r) {
            // COLMAP's camera is OpenCV's (+Y down, looks down +Z); OpenGL's is its y and z axes negated.
            f.r[r] = {c2w.m[r][0], -c2w.m[r][1], -c2w.m[r][2]};
            f.t[r] = c2w.m[r][3];
        }
        f.r = matmul(world_swap, f.r);
        f.t = mat_vec(world_swap, f.t);
        up = add(up, Vec3d{f.r[0][1], f.r[1][1], f.r[2][1]});
        frames.push_back(f);
    }
    // Cameras held upright on average: their mean image-up direction becomes the world's +z. A zero sum
    // (e.g. cameras rolled half and half) leaves the world as it is.
    const M3 level =
        length(up) > 1e-12 ? rotation_between(up, {0, 0, 1}) : M3{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    for (auto& f : frames) {
        f.r = matmul(level, f.r);
        f.t = mat_vec(level, f.t);
    }

    // The centre of attention: the weighted mean of the nearest points of every pair of optical axes.
    Vec3d centre{0, 0, 0};
    double total_weight = 0;
    for (const auto& f : frames)
        for (const auto& g : frames) {
            const auto [p, w] = closest_point_of_two_lines(f.t, {f.r[0][2], f.r[1][2], f.r[2][2]}, g.t,
                                                           {g.r[0][2], g.r[1][2], g.r[2][2]});
            if (w > 1e-5) {
                centre = add(centre, mul(p, w));
                total_weight += w;
            }
        }
    if (total_weight > 0) centre = mul(centre, 1.0 / total_weight);

    double mean_distance = 0;
    for (const auto& f : frames) mean_distance += length(sub(f.t, centre));
    mean_distance /= double(frames.size());
    if (!(mean_distance > 1e-12) || !std::isfinite(mean_distance))
        throw Error("COLMAP model: every camera sits at the centre of attention; cannot scale the scene");
    const double scale = settings.mean_camera_distance / mean_distance;

    NerfPoses out;
    const M3 turn = matmul(level, world_swap);
    for (size_t r = 0; r < 3; ++r) {
        for (size_t c = 0; c < 3; ++c) out.world_from_colmap.m[r][c] = turn[r][c] * scale;
        out.world_from_colmap.m[r][3] = -centre[r] * scale;
    }
    // turn is a rotation: its inverse is its transpose.
    for (size_t r = 0; r < 3; ++r)
        out.centre_colmap[r] = turn[0][r] * centre[0] + turn[1][r] * centre[1] + turn[2][r] * centre[2];
    for (size_t i = 0; i < frames.size(); ++i) {
        const ColmapCamera& cam = *model.find_camera(images[i]->camera_id);
        PosedFrame pf;
        pf.name = images[i]->name;
        pf.intrinsics = cam.intrinsics();
        pf.width = int(cam.width);
        pf.height = int(cam.height);
        for (size_t r = 0; r < 3; ++r) {
            for (size_t c = 0; c < 3; ++c) pf.camera_to_world.m[r][c] = frames[i].r[r][c];
            pf.camera_to_world.m[r][3] = (frames[i].t[r] - centre[r]) * scale;
        }
        out.frames.push_back(pf);
    }
    return out;
}

namespace {

void put_intrinsics(nlohmann::json& j, const PosedFrame& f) {
    const Intrinsics& k = f.intrinsics;
    j["w"] = f.width;
    j["h"] = f.height;
    j["fl_x"] = k.fx;
    j["fl_y"] = k.fy;
    j["cx"] = k.cx;
    j["cy"] = k.cy;
    j["k1"] = k.k1;
    j["k2"] = k.k2;
    j["p1"] = k.p1;
    j["p2"] = k.p2;
    j["camera_angle_x"] = 2 * std::atan(0.5 * f.width / k.fx);
    j["camera_angle_y"] = 2 * std::atan(0.5 * f.height / k.fy);
}

}  // namespace

void write_transforms(const ColmapModel& model, const fs::path& json_path,
                      const TransformsSettings& settings) {
    if (settings.aabb_scale < 1)
        throw Error(json_path.string() + ": 'aabb_scale' must be at least 1, got " +
                    std::to_string(settings.aabb_scale));
    const NerfPoses poses = nerf_poses(model, settings);
    const fs::path json_dir = fs::absolute(json_path).parent_path().lexically_normal();
    const fs::path images =
        settings.images_folder.is_absolute() ? settings.images_folder : json_dir / settings.images_folder;

    bool one_camera = true;
    for (const auto& im : model.images) one_camera &= im.camera_id == model.images.front().camera_id;

    nlohmann::json j;
    if (one_camera) put_intrinsics(j, poses.frames.front());
    j["aabb_scale"] = settings.aabb_scale;
    j["frames"] = nlohmann::json::array();
    for (const auto& f : poses.frames) {
        nlohmann::json fr;
        const fs::path image = (images / f.name).lexically_normal();
        const fs::path rel = image.lexically_relative(json_dir);
        fr["file_path"] = (rel.empty() ? image : rel).generic_string();
        if (!one_camera) put_intrinsics(fr, f);
        nlohmann::json m = nlohmann::json::array();
        for (size_t r = 0; r < 4; ++r)
            m.push_back({f.camera_to_world.m[r][0], f.camera_to_world.m[r][1], f.camera_to_world.m[r][2],
                         f.camera_to_world.m[r][3]});
        fr["transform_matrix"] = m;
        j["frames"].push_back(fr);
    }

    write_text_atomic(json_path, j.dump(2) + "\n");
}

}  // namespace npt::capture
