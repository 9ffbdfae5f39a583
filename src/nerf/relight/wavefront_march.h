// Many model-space rays marched through a NeRF together: each round every live ray takes its next few samples
// (the occupancy grid's march, ray_march.h, on the CPU in parallel), all of them are evaluated as one batch by a
// FieldQuery (CPU chunks or the GPU), and each ray composites its own in order. Rays leave once opaque (T < 1e-4),
// at their scattering event, or at the end of the box. The same quadrature as the renderer's NeRF march.
#pragma once

#include <cstddef>
#include <vector>

#include "core/vec.h"
#include "nerf/nerf_model.h"
#include "nerf/relight/field_query.h"

namespace npt::nerf {

enum class WaveMode {
    radiance,  // transmittance and the emitted colour (linear), as a camera ray of the emissive renderer
    event,     // where the optical depth first reaches tau_target (the scattering event of a relit path)
    depth,     // transmittance and the weighted distance (density only: no colour is evaluated)
};

struct WaveRay {
    Ray ray;              // model space, unit direction
    float jitter = 0.5f;  // lattice offset in [0, 1)
    float tau_target = 0.0f;  // WaveMode::event
    // Results.
    float transmittance = 1.0f;  // 0 once below 1e-4
    Rgb radiance{0.0f};
    float depth = 0.0f;  // radiance and depth modes: sum of the volume weights times the distance along the ray
    bool has_event = false;
    Vec3 event_position{0.0f};
};

// Live rays in one round at most (bounds a round's buffers, ~120 MB): callers batching rays for a GPU fill one.
constexpr size_t k_wavefront_round_rays = size_t(1) << 17;

void march_wavefront(const NerfModel& model, FieldQuery& query, std::vector<WaveRay>& rays, WaveMode mode);

}  // namespace npt::nerf
