#include "scene/mesh_utils.h"

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

void transform_mesh(Mesh& mesh, const Mat4& m) {
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
