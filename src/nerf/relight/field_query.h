// The NeRF evaluated at many points at once, for work that marches many rays together (the relight stage's
// wavefront marcher): on the CPU in parallel chunks (field_batch.h), on a GPU through the CUDA evaluator
// (nerf/backend: make_field_query). One interface, so the stage's logic is written once.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "core/vec.h"
#include "nerf/nerf_model.h"
#include "nerf/relight/wave_ray.h"

namespace npt::nerf {

class FieldQuery {
  public:
    virtual ~FieldQuery() = default;
    // sigma (per model unit) at n model-space points; with dirs (unit) also the colour (sigmoid outputs, the
    // stored sRGB-encoded values) into rgb; dirs null: density only, rgb untouched.
    virtual void evaluate(const Vec3* positions, const Vec3* dirs, size_t n, float* sigma, Rgb* rgb) = 0;
    // The whole wavefront march of `rays` on the query's own device, with march_wavefront's arithmetic (its
    // results, up to float rounding); false where the query cannot, and march_wavefront marches with evaluate().
    virtual bool march(std::vector<WaveRay>& rays, WaveMode mode) {
        (void)rays;
        (void)mode;
        return false;
    }
    // Rays a caller should hand march_wavefront per call: a GPU's march wants many more than a CPU round holds.
    virtual size_t batch_rays() const { return k_wavefront_round_rays; }
};

// The model must outlive the query.
std::unique_ptr<FieldQuery> make_cpu_field_query(const NerfModel& model);

}  // namespace npt::nerf
