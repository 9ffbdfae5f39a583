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
// Then checks the result in world space (validate_world_mesh): finite local data can overflow a float after
// a large transform (a `matrix` entry of 3e38, a scale of 1e30).
void transform_mesh(Mesh& mesh, const Mat4& m, const std::string& where);

// Throws npt::Error "<where>: position I is ... in world space (after the node transforms)" when a position
// is not finite or lies beyond k_max_world_coordinate, or a normal is not finite.
void validate_world_mesh(const Mesh& mesh, const std::string& where);

// The same check for one world-space point: `what` names it ("camera position", "light position").
void check_world_point(Vec3 p, const std::string& where, const std::string& what);

// A volume cube's placement: local_to_world finite and invertible, and the cube's 8 corners within
// k_max_world_coordinate. Throws npt::Error naming `where`.
void check_volume_placement(const VolumeInstance& v, const std::string& where);

// Bounds of the positions; (0,0,0)-(0,0,0) when empty.
void mesh_bounds(const Mesh& mesh, Vec3& lo, Vec3& hi);

}  // namespace npt::scene
