// Many model-space rays marched through a NeRF together: each round every live ray takes its next few samples
// (the occupancy grid's march, ray_march.h, on the CPU in parallel), all of them are evaluated as one batch by a
// FieldQuery, and each ray composites its own in order. Rays leave once opaque (T < 1e-4), at their scattering
// event, or at the end of the box. The same quadrature as the renderer's NeRF march. A query that can march on
// its own device (the GPU's: FieldQuery::march) takes the whole march, rounds and all, with the same arithmetic.
#pragma once

#include <cstddef>
#include <vector>

#include "core/vec.h"
#include "nerf/nerf_model.h"
#include "nerf/relight/field_query.h"
#include "nerf/relight/wave_ray.h"

namespace npt::nerf {

void march_wavefront(const NerfModel& model, FieldQuery& query, std::vector<WaveRay>& rays, WaveMode mode);

}  // namespace npt::nerf
