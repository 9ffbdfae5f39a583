// Where the captured object stands in its model (issue 25): the object frame (origin at the base centre on the
// supporting plane, +Z up, metres when the capture was told the object's height) and the object's box in it.
// A model file carries it in its OBJF section (docs/formats.md); a `volume` cube holding such a model places
// the object frame on the cube's local space (Y up), so an identity node stands the object on y = 0 at the
// origin, at its real size.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "core/transform.h"
#include "core/vec.h"
#include "nerf/nerf_placement.h"
#include "nerf/object_cut.h"

namespace npt::nerf {

struct ObjectFrame {
    // Object space -> the training world (the cameras' space, transforms.json's coordinates): a similarity
    // (rotation, uniform scale, translation) without mirroring.
    Mat4 object_to_world;
    Vec3 box_min{-0.5f, -0.5f, 0.0f}, box_max{0.5f, 0.5f, 1.0f};  // the object's box, object space
    bool metric = false;  // object units are metres; else the capture's units
    // Renders of the model show only what lies in the box (eval and view as with --object, bake's voxels; scenes
    // cut it with "placement": "object" anyway): set by `nerfpt isolate`, whose occupancy cut keeps the cells that straddle
    // the box and the supporting plane, so that the exact cut is the renderer's. Training clears it.
    bool object_only = false;
    // Object units per training-world unit (the similarity's scale, inverted).
    double units_per_world() const;
};

// The OBJF section's JSON: {"version": 1, "object_to_world": [16 numbers, row-major], "box": {"min": [x, y, z],
// "max": [x, y, z]}, "metric": bool, "object_only": bool}; object_only is written only when true (older readers
// ignore it).
nlohmann::json object_frame_to_json(const ObjectFrame& frame);
// Throws npt::Error "WHERE: FIELD: what is wrong" for another version, missing or non-finite numbers, an empty
// box, or an object_to_world that is not a proper similarity.
ObjectFrame object_frame_from_json(const nlohmann::json& j, const std::string& where);

// The cube's local space (Y up, object units) -> object space (Z up): (x, y, z) -> (x, -z, y), a quarter turn.
Vec3 local_to_object(Vec3 local);
Vec3 object_to_local(Vec3 object);
// The object's box in the cube's local space.
void object_local_box(const ObjectFrame& frame, Vec3* local_min, Vec3* local_max);
// Local -> object -> training world -> model, with world_to_model the model's.
LocalToModel object_local_to_model(const ObjectFrame& frame, const Mat4& world_to_model);
// The model-space bounding box of the object's box (for the march; it is rotated in model space).
CropBox object_model_box(const ObjectFrame& frame, const Mat4& world_to_model);
// Model space -> object space (+Z up, the supporting plane at z = 0), with world_to_model the model's.
Mat4 model_to_object(const ObjectFrame& frame, const Mat4& world_to_model);
// The centre of the object's box in the training world.
Vec3 object_box_centre_world(const ObjectFrame& frame);
// The test of model-space points against the object's box (object_cut.h), active.
ObjectCut object_cut(const ObjectFrame& frame, const Mat4& world_to_model);

}  // namespace npt::nerf
