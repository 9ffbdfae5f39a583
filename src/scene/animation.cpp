#include "scene/animation.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "scene/mesh_utils.h"

namespace npt::scene {

namespace {

using Values = std::array<double, 4>;

Values key_value(const AnimationChannel& c, size_t key) {
    const int w = c.width();
    // CUBICSPLINE keys are (in-tangent, value, out-tangent): the value is the middle element.
    const size_t at = c.interpolation == Interpolation::CubicSpline ? (3 * key + 1) * size_t(w) : key * size_t(w);
    Values v{0, 0, 0, 0};
    for (int k = 0; k < w; ++k) v[size_t(k)] = c.values[at + size_t(k)];
    return v;
}

Values tangent(const AnimationChannel& c, size_t key, bool out) {
    const int w = c.width();
    const size_t at = (3 * key + (out ? 2 : 0)) * size_t(w);
    Values v{0, 0, 0, 0};
    for (int k = 0; k < w; ++k) v[size_t(k)] = c.values[at + size_t(k)];
    return v;
}

Values normalized(Values q) {
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (n > 0)
        for (double& x : q) x /= n;
    return q;
}

// Spherical interpolation along the shorter arc; nearly parallel quaternions fall back to a normalised lerp,
// where slerp's sin(theta) denominator loses its digits.
Values slerp(Values a, Values b, double u) {
    a = normalized(a);
    b = normalized(b);
    double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    if (d < 0) {
        for (double& x : b) x = -x;
        d = -d;
    }
    double wa = 1 - u, wb = u;
    if (d < 0.9995) {
        const double theta = std::acos(std::min(d, 1.0));
        const double s = std::sin(theta);
        wa = std::sin((1 - u) * theta) / s;
        wb = std::sin(u * theta) / s;
    }
    Values r;
    for (size_t k = 0; k < 4; ++k) r[k] = wa * a[k] + wb * b[k];
    return normalized(r);
}

Mat4 trs_matrix(const std::array<double, 3>& t, const Values& r, const std::array<double, 3>& s) {
    return Mat4::translation(t[0], t[1], t[2]) * Mat4::rotation_quat(r[0], r[1], r[2], r[3]) *
           Mat4::scale(s[0], s[1], s[2]);
}

bool same(const Mat4& a, const Mat4& b) {
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            if (a.m[size_t(r)][size_t(c)] != b.m[size_t(r)][size_t(c)]) return false;
    return true;
}

bool same(Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

bool same(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](Vec3 x, Vec3 y) { return same(x, y); });
}

Vec3 column(const Mat4& m, int c) { return {float(m.m[0][size_t(c)]), float(m.m[1][size_t(c)]), float(m.m[2][size_t(c)])}; }

}  // namespace

std::array<double, 4> sample_channel(const AnimationChannel& c, double t) {
    const size_t n = c.times.size();
    const int w = c.width();
    if (n == 0) return {0, 0, 0, w == 4 ? 1.0 : 0.0};
    if (n == 1 || t <= c.times.front()) return key_value(c, 0);
    if (t >= c.times.back()) return key_value(c, n - 1);
    // The key interval [times[i], times[i+1]) holding t.
    const size_t i = size_t(std::upper_bound(c.times.begin(), c.times.end(), t) - c.times.begin()) - 1;
    const double t0 = c.times[i], t1 = c.times[i + 1], dt = t1 - t0;
    const double u = (t - t0) / dt;
    switch (c.interpolation) {
        case Interpolation::Step:
            return key_value(c, i);
        case Interpolation::Linear: {
            const Values a = key_value(c, i), b = key_value(c, i + 1);
            if (c.path == AnimationPath::Rotation) return slerp(a, b, u);
            Values r{0, 0, 0, 0};
            for (size_t k = 0; k < size_t(w); ++k) r[k] = a[k] + u * (b[k] - a[k]);
            return r;
        }
        case Interpolation::CubicSpline: {
            // glTF Appendix C: p(u) = h00 v_i + h10 dt b_i + h01 v_{i+1} + h11 dt a_{i+1}, with b the out-tangent
            // of key i and a the in-tangent of key i+1 (tangents are per second, hence the dt).
            const Values p0 = key_value(c, i), p1 = key_value(c, i + 1);
            const Values m0 = tangent(c, i, true), m1 = tangent(c, i + 1, false);
            const double u2 = u * u, u3 = u2 * u;
            const double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2, h11 = u3 - u2;
            Values r{0, 0, 0, 0};
            for (size_t k = 0; k < size_t(w); ++k)
                r[k] = h00 * p0[k] + h10 * dt * m0[k] + h01 * p1[k] + h11 * dt * m1[k];
            return c.path == AnimationPath::Rotation ? normalized(r) : r;
        }
    }
    return key_value(c, i);
}

std::vector<Mat4> world_transforms(const std::vector<AnimationNode>& nodes, const Animation* animation, double t,
                                   const Mat4& placement) {
    std::vector<std::array<double, 3>> translation(nodes.size()), scale(nodes.size());
    std::vector<Values> rotation(nodes.size());
    for (size_t i = 0; i < nodes.size(); ++i) {
        translation[i] = nodes[i].translation;
        rotation[i] = nodes[i].rotation;
        scale[i] = nodes[i].scale;
    }
    if (animation)
        for (const AnimationChannel& c : animation->channels) {
            if (c.node < 0 || size_t(c.node) >= nodes.size()) continue;  // refused by the loader
            const Values v = sample_channel(c, t);
            const size_t n = size_t(c.node);
            if (c.path == AnimationPath::Translation) translation[n] = {v[0], v[1], v[2]};
            if (c.path == AnimationPath::Rotation) rotation[n] = v;
            if (c.path == AnimationPath::Scale) scale[n] = {v[0], v[1], v[2]};
        }
    // Parents first: resolved on demand with memoisation (the loader refused cycles).
    std::vector<Mat4> world(nodes.size());
    std::vector<char> done(nodes.size(), 0);
    for (size_t i = 0; i < nodes.size(); ++i) {
        std::vector<size_t> chain;
        for (size_t n = i; !done[n];) {
            chain.push_back(n);
            if (nodes[n].parent < 0) break;
            n = size_t(nodes[n].parent);
        }
        for (size_t k = chain.size(); k-- > 0;) {
            const size_t n = chain[k];
            const Mat4 local = nodes[n].has_matrix ? nodes[n].matrix : trs_matrix(translation[n], rotation[n], scale[n]);
            world[n] = (nodes[n].parent < 0 ? placement : world[size_t(nodes[n].parent)]) * local;
            done[n] = 1;
        }
    }
    return world;
}

void place_camera(Camera& cam, const Mat4& world, const std::string& where) {
    cam.position = world.transform_point(Vec3(0.0f));
    check_world_point(cam.position, where, "position");
    // Strip scale and shear: forward from -Z, right from X made orthogonal to it, up completes the frame.
    Vec3 f = -column(world, 2), x = column(world, 0);
    if (!(length(f) > 0.0f)) throw Error(where + ": node transform is degenerate");
    f = normalize(f);
    Vec3 r = x - f * dot(x, f);
    if (!(length(r) > 1e-12f)) throw Error(where + ": node transform is degenerate");
    cam.forward = f;
    cam.right = normalize(r);
    cam.up = cross(cam.right, cam.forward);
}

PoseChanges pose_scene(Scene& scene, double t) {
    PoseChanges changes;
    if (!scene.animation) return changes;
    SceneAnimation& a = *scene.animation;
    if (!std::isfinite(t)) throw Error(a.file + ": animation time is not finite");
    const std::vector<Mat4> world = world_transforms(a.nodes, &a.animation, t, a.placement);
    const auto node_world = [&](int node) -> const Mat4& { return world[size_t(node)]; };

    for (MeshBinding& b : a.meshes) {
        const Mat4& w = node_world(b.node);
        const std::string where = a.file + ": mesh '" + b.local.name + "' at " + std::to_string(t) + " s";
        if (!w.is_finite()) throw Error(where + ": transform is not finite");
        if (std::abs(w.determinant3()) < 1e-30) throw Error(where + ": transform is singular (a zero scale)");
        Mesh moved = b.local;
        transform_mesh(moved, w, where);
        Mesh& m = scene.meshes[b.mesh];
        if (same(moved.positions, m.positions) && same(moved.normals, m.normals) && moved.indices == m.indices) continue;
        m.positions = std::move(moved.positions);
        m.normals = std::move(moved.normals);
        m.indices = std::move(moved.indices);
        changes.meshes.push_back(b.mesh);
    }
    for (const NodeBinding& b : a.cameras) {
        Camera& cam = scene.cameras[b.index];
        const Camera before = cam;
        place_camera(cam, node_world(b.node), a.file + ": camera '" + cam.name + "' at " + std::to_string(t) + " s");
        changes.cameras |= !(same(before.position, cam.position) && same(before.forward, cam.forward) &&
                             same(before.right, cam.right) && same(before.up, cam.up));
    }
    for (const NodeBinding& b : a.lights) {
        PunctualLight& l = scene.lights[b.index];
        const Mat4& w = node_world(b.node);
        const std::string where = a.file + ": light '" + l.name + "' at " + std::to_string(t) + " s";
        const Vec3 p = w.transform_point(Vec3(0.0f));
        check_world_point(p, where, "position");
        const Vec3 d = w.transform_vector(Vec3(0, 0, -1));
        if (!(length(d) > 0.0f)) throw Error(where + ": light direction is degenerate");
        const Vec3 dir = normalize(d);
        changes.lights |= !(same(p, l.position) && same(dir, l.direction));
        l.position = p;
        l.direction = dir;
    }
    for (const NodeBinding& b : a.volumes) {
        VolumeInstance& v = scene.volumes[b.index];
        if (same(v.local_to_world, node_world(b.node))) continue;
        v.local_to_world = node_world(b.node);
        check_volume_placement(v, a.file + ": volume '" + v.name + "' at " + std::to_string(t) + " s");
        changes.volumes = true;
    }
    return changes;
}

}  // namespace npt::scene
