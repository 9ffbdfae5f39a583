// The `object` stage of `nerfpt capture` (issue 25): the subject's geometry from COLMAP's sparse model and the
// cameras (capture/subject/), turned into the object frame that capture.json records and the model carries.
#pragma once

#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>

#include "nerf/object_frame.h"

namespace npt::cli {

// What the stage found: `record` is capture.json's `object` entry (docs/formats.md); `frame` is set when a
// supporting plane and the object on it were found (else record holds "found": false and the reason).
struct ObjectStageResult {
    nlohmann::json record;
    std::optional<nerf::ObjectFrame> frame;
    std::string line;  // one line for the terminal: what was found, in which units
};

// Reads the COLMAP model in `colmap_model` (the one transforms.json was written from), places its points and
// cameras as transforms.json does, and finds the subject. height_m > 0: the object's real height in metres,
// which makes the object frame metric; 0: the frame stays in capture units.
ObjectStageResult object_stage(const std::filesystem::path& colmap_model, double height_m);

// The object frame recorded in capture.json's `object` entry, if it has one.
std::optional<nerf::ObjectFrame> object_frame_of_record(const nlohmann::json& record);

// The corners of the recorded object's box in the training world, widened to take in what the first box from
// sparse points misses (the refined box is wider), for training's subject rays; nullopt without an object.
std::optional<std::array<Vec3, 8>> subject_box_of_record(const nlohmann::json& record);

// After training: refines the recorded box with the model's occupancy grid (capture/subject's
// refine_box_with_field; redone when `retrained` or the model's step count differs from the one recorded), updates `record`
// (the object entry: "sparse" keeps the first box, "dense" says what the model gave) and writes the object frame
// into the model file unless it already holds exactly that frame.
struct ObjectAttach {
    bool record_changed = false, model_written = false;
    std::string line;  // what the refinement found, empty when it was not redone
};
ObjectAttach attach_object(const std::filesystem::path& model, nlohmann::json& record, double height_m,
                           bool retrained);

}  // namespace npt::cli
