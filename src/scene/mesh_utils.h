// Checks and fix-ups shared by the mesh loaders (glTF, OBJ): finiteness and index validation with one-line
// errors, smooth normal generation, mirroring, and applying a placement transform.
#pragma once

#include <string>

#include "core/transform.h"
#include "scene/scene.h"

namespace npt::scene {

// Throws npt::Error "<where>: ..." when a position or normal is NaN/Inf, an index is out of range, or the
// index count is not a multiple of 3. `where` names the file and mesh, e.g. "scene.gltf: mesh 'floor'".
void validate_mesh(const Mesh& mesh, const std::string& where);

// Area-weighted smooth vertex normals (for meshes that need a shading frame but carry no normals).
void generate_smooth_normals(Mesh& mesh);

// Maps positions and normals through `m` (normals by the inverse transpose, renormalised) and reverses the
// triangle winding when `m` mirrors, so the front face keeps pointing along the counter-clockwise normal.
void transform_mesh(Mesh& mesh, const Mat4& m);

// Bounds of the positions; (0,0,0)-(0,0,0) when empty.
void mesh_bounds(const Mesh& mesh, Vec3& lo, Vec3& hi);

}  // namespace npt::scene
