#include "scene/mesh_utils.h"

#include <fmt/format.h>

#include <cmath>
#include <utility>

#include "core/error.h"

namespace npt::scene {

void validate_mesh(const Mesh& mesh, const std::string& where) {
    for (size_t i = 0; i < mesh.positions.size(); ++i)
        if (!is_finite(mesh.positions[i]))
            throw Error(where + ": position " + std::to_string(i) + " is not finite (NaN or Inf)");
    for (size_t i = 0; i < mesh.normals.size(); ++i)
        if (!is_finite(mesh.normals[i]))
            throw Error(where + ": normal " + std::to_string(i) + " is not finite (NaN or Inf)");
    for (size_t i = 0; i < mesh.uvs.size(); ++i)
        if (!std::isfinite(mesh.uvs[i].x) || !std::isfinite(mesh.uvs[i].y))
            throw Error(where + ": texture coordinate " + std::to_string(i) + " is not finite (NaN or Inf)");
    if (mesh.indices.size() % 3 != 0)
        throw Error(where + ": " + std::to_string(mesh.indices.size()) +
                    " indices is not a whole number of triangles");
    for (size_t i = 0; i < mesh.indices.size(); ++i)
        if (mesh.indices[i] >= mesh.positions.size())
            throw Error(where + ": index " + std::to_string(i) + " = " + std::to_string(mesh.indices[i]) +
                        " is out of range (" + std::to_string(mesh.positions.size()) + " vertices)");
}

void generate_smooth_normals(Mesh& mesh) {
    std::vector<Vec3> n(mesh.positions.size(), Vec3(0.0f));
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
        // The unnormalised cross product is twice the triangle area: area weighting for free.
        Vec3 fn = cross(mesh.positions[b] - mesh.positions[a], mesh.positions[c] - mesh.positions[a]);
        n[a] += fn;
        n[b] += fn;
        n[c] += fn;
    }
    for (auto& v : n) {
        float len = length(v);
        v = len > 0.0f ? v / len : Vec3(0.0f, 0.0f, 1.0f);
    }
    mesh.normals = std::move(n);
}

namespace {

bool within_world(Vec3 p) {
    return is_finite(p) && std::abs(p.x) <= k_max_world_coordinate &&
           std::abs(p.y) <= k_max_world_coordinate && std::abs(p.z) <= k_max_world_coordinate;
}

std::string world_problem(Vec3 p) {
    const std::string xyz = fmt::format("({:g}, {:g}, {:g})", p.x, p.y, p.z);
    if (!is_finite(p)) return "is not finite in world space " + xyz + ", after the transforms";
    return fmt::format("is beyond +-{:g} in world space {}, after the transforms (the range rays can reach)",
                       k_max_world_coordinate, xyz);
}

}  // namespace

void validate_world_mesh(const Mesh& mesh, const std::string& where) {
    for (size_t i = 0; i < mesh.positions.size(); ++i)
        if (!within_world(mesh.positions[i]))
            throw Error(where + ": position " + std::to_string(i) + " " + world_problem(mesh.positions[i]));
    for (size_t i = 0; i < mesh.normals.size(); ++i)
        if (!is_finite(mesh.normals[i]))
            throw Error(where + ": normal " + std::to_string(i) + " is not finite in world space");
}

void check_world_point(Vec3 p, const std::string& where, const std::string& what) {
    if (!within_world(p)) throw Error(where + ": " + what + " " + world_problem(p));
}

void check_volume_placement(const VolumeInstance& v, const std::string& where) {
    if (!v.local_to_world.is_finite()) throw Error(where + ": transform is not finite");
    if (!(std::abs(v.local_to_world.determinant3()) > 1e-30))
        throw Error(where + ": transform is singular (a zero scale?): the volume cube has no inside");
    for (int c = 0; c < 8; ++c) {
        const Vec3 local(c & 1 ? v.local_max.x : v.local_min.x, c & 2 ? v.local_max.y : v.local_min.y,
                         c & 4 ? v.local_max.z : v.local_min.z);
        check_world_point(v.local_to_world.transform_point(local), where, "cube corner");
    }
}

void transform_mesh(Mesh& mesh, const Mat4& m, const std::string& where) {
    for (auto& p : mesh.positions) p = m.transform_point(p);
    if (!mesh.normals.empty()) {
        const Mat4 inv = m.inverse();
        for (auto& nrm : mesh.normals) {
            double x = nrm.x, y = nrm.y, z = nrm.z;
            Vec3 r{float(inv.m[0][0] * x + inv.m[1][0] * y + inv.m[2][0] * z),
                   float(inv.m[0][1] * x + inv.m[1][1] * y + inv.m[2][1] * z),
                   float(inv.m[0][2] * x + inv.m[1][2] * y + inv.m[2][2] * z)};
            float len = length(r);
            nrm = len > 0.0f ? r / len : r;
        }
    }
    if (m.determinant3() < 0.0)
        for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
            std::swap(mesh.indices[t + 1], mesh.indices[t + 2]);
    validate_world_mesh(mesh, where);
}

void mesh_bounds(const Mesh& mesh, Vec3& lo, Vec3& hi) {
    if (mesh.positions.empty()) {
        lo = hi = Vec3(0.0f);
        return;
    }
    lo = hi = mesh.positions[0];
    for (const auto& p : mesh.positions) {
        lo = vmin(lo, p);
        hi = vmax(hi, p);
    }
}

}  // namespace npt::scene
