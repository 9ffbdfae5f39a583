// A trained (or training) NeRF: its configuration, where it sits relative to the training cameras, its
// parameters and its occupancy grid. The per-point query (NerfFieldView) is in nerf_field.h.
#pragma once

#include <math.h>

#include <cstdint>
#include <optional>
#include <vector>

#include "core/transform.h"
#include "nerf/adam.h"
#include "nerf/dataset.h"
#include "nerf/image_exposure.h"
#include "nerf/nerf_config.h"
#include "nerf/nerf_field.h"
#include "nerf/object_frame.h"
#include "nerf/occupancy_grid.h"
#include "nerf/ray_march.h"
#include "nerf/relight/relight_model.h"

namespace npt::nerf {

NerfLayout make_layout(const NerfConfig& config, float aabb_scale);

// What only training needs: the raw (not averaged) parameters and the optimizer's state. Randomness is a
// function of (seed, step), so the step is all that is needed to continue exactly.
struct TrainingState {
    std::vector<float> params;
    AdamState adam;
    double elapsed_seconds = 0;  // training time so far, for --time across resumes
    uint32_t rays_per_step = 0;  // the adaptive batch size in rays for the next step (0: not yet known)
    ExposureState exposure;      // per training image (training.exposure_per_image), else empty
};

struct NerfModel {
    NerfConfig config;
    float aabb_scale = 1.0f;
    // Training-camera (world) space to model space: instant-ngp's p * scale + offset followed by its axis cycle
    // (x, y, z) <- (y, z, x), so that model space is instant-ngp's and its snapshots import unchanged.
    Mat4 world_to_model;
    std::vector<float> params;  // what renders: the averaged (EMA) parameters
    OccupancyGrid occupancy;
    std::optional<TrainingState> training;
    std::optional<RelightFields> relight;  // present for relightable models (`nerfpt train --relightable`)
    // The training cameras' viewing directions (optical axes), unit, model axes: the directions in which the
    // colour network was trained, which a bake averages its colour over (bake/bake_grid.h). Empty for models
    // written before they were stored (and for imported snapshots).
    std::vector<Vec3> view_directions;
    // Where the captured object stands (`nerfpt capture`, object_frame.h); absent for other models.
    std::optional<ObjectFrame> object;

    NerfLayout layout() const { return make_layout(config, aabb_scale); }
    NerfFieldView field() const { return {layout(), params.data()}; }
    MarchParams march_params() const;
    bool relightable() const { return relight.has_value() && !relight->params.empty(); }
    // The intrinsic fields for renderers; invalid (params nullptr) when the model is not relightable.
    IntrinsicFieldView intrinsic() const {
        if (!relightable()) return {};
        return {make_intrinsic_layout(relight->config, aabb_scale), relight->params.data()};
    }
};

// A fresh model for a data set: parameters initialised (hash grid uniform in +-1e-4, MLP weights
// Xavier-uniform, from config.training.seed), every occupancy cell occupied.
NerfModel create_model(const NerfConfig& config, float aabb_scale, const Mat4& world_to_model);

// The data set's cameras' optical axes (camera -z, OpenGL convention) in model axes, unit length: what
// NerfModel::view_directions stores.
std::vector<Vec3> training_view_directions(const std::vector<Camera>& cameras, const Mat4& world_to_model);

// instant-ngp's world-to-model map for a data set's scale and offset.
Mat4 ngp_world_to_model(float scale, Vec3 offset);

}  // namespace npt::nerf
