// Renders what a pinhole camera sees of a NeRF model on its own (no scene): for `nerfpt eval` and `nerfpt
// view`. Rays march through the occupancy grid; the field is evaluated in batches, a growing window of
// samples per ray at a time, so that rays which become opaque early stop costing work.
#pragma once

#include <functional>

#include "core/image.h"
#include "nerf/dataset.h"
#include "nerf/nerf_model.h"
#include "nerf/object_cut.h"

namespace npt::nerf {

struct ViewOptions {
    Rgb background{1.0f, 1.0f, 1.0f};  // the literature evaluates NeRF-synthetic on white
    // The GPU renderer's samples per live ray in its first round (they double each round, up to 64); 0: its
    // default. The image does not depend on it, only the time; the CPU ignores it.
    int gpu_first_round = 0;
    // Only what lies inside the model's object box (its object frame, issue 25) is seen: samples outside it are
    // dropped, as a `volume` cube with "placement": "object" cuts the model (object_cut.h, the same test on the
    // CPU and the GPU). A model without an object frame is an error.
    bool object_only = false;
};

// The object test a view renderer applies for `options`: active with object_only, or for a model whose object
// frame says object_only (an isolated model, object_frame.h). Throws npt::Error when object_only is asked of a
// model without an object frame.
ObjectCut view_object_cut(const NerfModel& model, const ViewOptions& options);

// Returns an RGBA image: colour composited over the background, as the training images store it (sRGB-encoded
// values in [0,1], not linear light), and alpha = 1 - transmittance. `progress(done_rows, rows)` is called
// from one thread at a time; returning false stops the render early (throws npt::Error("interrupted")).
Image render_view(const NerfModel& model, const Camera& camera, const ViewOptions& options,
                  const std::function<bool(size_t, size_t)>& progress = {});

}  // namespace npt::nerf
