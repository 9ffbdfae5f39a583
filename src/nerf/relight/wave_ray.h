// A ray of the relight stage's wavefront march (wavefront_march.h) and what it asks for: plain data, so that
// a GPU marches an array of them as the CPU does (nerf/cuda/cuda_wave_march.h).
#pragma once

#include <math.h>

#include <cstddef>

#include "core/platform.h"
#include "core/srgb.h"
#include "core/vec.h"

namespace npt::nerf {

enum class WaveMode {
    radiance,  // transmittance and the emitted colour (linear), as a camera ray of the emissive renderer
    event,     // where the optical depth first reaches tau_target (the scattering event of a relit path)
    depth,     // transmittance and the weighted distance (density only: no colour is evaluated)
};

struct WaveRay {
    Ray ray;                  // model space, unit direction
    float jitter = 0.5f;      // lattice offset in [0, 1)
    float tau_target = 0.0f;  // WaveMode::event
    // Results.
    float transmittance = 1.0f;  // 0 once below 1e-4
    Rgb radiance{0.0f};
    // Radiance and depth modes: the sum of the volume weights times the distance along the ray.
    float depth = 0.0f;
    bool has_event = false;
    Vec3 event_position{0.0f};
};

// A ray's march ends once its transmittance falls below this (ln 1e-4), as the renderer's.
constexpr float k_wave_log_stop = -9.2103404f;

// One sample of a ray's march composited into it, front to back (march_wavefront's arithmetic on either
// device): `pos` the sample, `d` its optical depth (sigma dt), `rgb` its stored colour (sRGB-encoded; read in
// radiance mode only); log_t and tau carry the ray's log transmittance and optical depth between samples.
// True where the ray ends at this sample: its event, or opaque.
NPT_HD inline bool wave_composite(WaveMode mode, WaveRay& r, float& log_t, float& tau, Vec3 pos, float d,
                                  Rgb rgb) {
    if (!(d > 0.0f)) return false;
    if (mode == WaveMode::event) {
        tau += d;
        if (tau < r.tau_target) return false;
        r.has_event = true;
        r.event_position = pos;
        return true;
    }
    const float w = expf(log_t) * -expm1f(-d);
    if (mode == WaveMode::radiance)
        r.radiance += Rgb(srgb_to_linear(rgb.x), srgb_to_linear(rgb.y), srgb_to_linear(rgb.z)) * w;
    r.depth += w * dot(pos - r.ray.o, r.ray.d);
    log_t -= d;
    return log_t < k_wave_log_stop;
}

// The ray's transmittance once its march has ended.
NPT_HD inline float wave_transmittance(WaveMode mode, float log_t, float tau) {
    return mode == WaveMode::event ? expf(-tau) : (log_t < k_wave_log_stop ? 0.0f : expf(log_t));
}

// Live rays in one round of the CPU's march at most (bounds a round's buffers, ~120 MB); callers batch this
// many rays per call unless the query asks for more (FieldQuery::batch_rays).
constexpr size_t k_wavefront_round_rays = size_t(1) << 17;

}  // namespace npt::nerf
