// Free-flight sampling in a relit NeRF (a NeRF shaded as a scattering medium lit by the scene): the ray is
// marched exactly as the emissive integrator marches it (volume_integrator.h: the same model-space lattice from
// the same offset, the same occupancy skipping, the same per-step quadrature), its optical depth accumulated,
// and a scattering event taken in step i with probability T_i (1 - exp(-sigma_i dt_i)): the event lies where
// the optical depth first reaches a target drawn as -ln(1 - u). So a path that returns radiance c from every
// event estimates exactly the emissive quadrature of colour c. Templated on the field (density(p) and
// intrinsic(p) in model space) so that tests drive it with analytic fields; NPT_HD.
#pragma once

#include <math.h>

#include "core/platform.h"
#include "core/vec.h"
#include "media/volume.h"
#include "media/volume_ray.h"
#if !defined(__CUDACC__)
#include <vector>

#include "nerf/field_batch.h"  // the CPU evaluates densities in batches
#endif

namespace npt::media {

// A relit NeRF volume's fields: density from the NeRF, the intrinsic fields from its relight section.
struct RelitNerfField {
    nerf::NerfFieldView nerf;
    nerf::IntrinsicFieldView intrinsic_field;
    NPT_HD float density(Vec3 p) const { return nerf.density(p); }
    NPT_HD nerf::IntrinsicSample intrinsic(Vec3 p) const { return intrinsic_field.query(p); }
};

NPT_HD NPT_INLINE RelitNerfField relit_field(const VolumeView& v) { return {v.nerf.field, v.nerf.intrinsic}; }

// One ray's free flight through the relit volumes it crosses (in the order they are marched).
struct FreeFlight {
    float target = INFINITY;    // the optical depth where the event happens; INFINITY: none (transmittance only)
    float tau = 0.0f;           // relit optical depth so far (sigma times density_scale times model-space dt)
    float tau_stop = INFINITY;  // marching stops past this depth (shadow rays: T < 1e-4 counts as 0)
    bool event = false;
    float t = 0.0f;             // the event's distance along the world ray
    int volume = -1;            // the event's volume (index into the scene's volumes)
    Vec3 p_model{0.0f};         // the event's sample position, in that volume's model space
    NPT_HD bool done() const { return event || tau > tau_stop; }
    // A march sample at model point p (world distance t) that stands for optical depth sigma_dt.
    NPT_HD void add(float sigma_dt, Vec3 p, float t_world) {
        if (!(sigma_dt > 0.0f)) return;  // also NaN
        tau += sigma_dt;
        if (tau >= target) {
            event = true;
            p_model = p;
            t = t_world;
        }
    }
};

// The target optical depth for u uniform in [0, 1): P(target <= tau) = 1 - exp(-tau).
NPT_HD NPT_INLINE float free_flight_target(float u) { return -log1pf(-fminf(u, 0.99999994f)); }

#if !defined(__CUDACC__)
// The densities of a window of samples: one at a time for any field, as one batch for a NeRF (field_batch.h,
// the MLP as matrix products; overload resolution prefers the non-template).
template <class Field>
inline void relit_density_batch(const Field& f, const std::vector<Vec3>& pos, std::vector<float>& sigma,
                                nerf::FieldBatch&) {
    sigma.resize(pos.size());
    for (size_t i = 0; i < pos.size(); ++i) sigma[i] = f.density(pos[i]);
}
inline void relit_density_batch(const RelitNerfField& f, const std::vector<Vec3>& pos, std::vector<float>& sigma,
                                nerf::FieldBatch& b) {
    nerf::field_forward(f.nerf.layout, f.nerf.params, pos.data(), nullptr, pos.size(), false, b);
    sigma.assign(b.sigma.begin(), b.sigma.begin() + std::ptrdiff_t(pos.size()));
}
#endif

// The free flight over [ta, tb] of the world ray through one relit NeRF volume: marched as march_nerf marches
// it (nerf_model_segment, march_ray_visit, sigma times density_scale over the model-space step), stopping at
// the event or at ff.tau_stop. On the CPU the densities are evaluated in windows (16, 32, ... 128), as the
// emissive march does.
template <class Field>
NPT_HD NPT_INLINE void march_relit(const VolumeView& v, const Field& field, const Ray& ray, float ta, float tb,
                                   float xi, FreeFlight& ff) {
    const NerfVolumeView& n = v.nerf;
    Ray mray;
    nerf::MarchParams mp = n.march;
    if (!nerf_model_segment(v, ray, ta, tb, &mray, &mp.t_max) || !(mp.t_max > 0.0f)) return;
    const float world_per_model = (tb - ta) / mp.t_max;
    const float scale = v.density_scale;
#if defined(__CUDACC__)  // both nvcc passes: per sample
    nerf::march_ray_visit(mp, n.occupancy, mray, xi, [&](const nerf::MarchSample& s) {
        ff.add(field.density(s.position) * scale * s.dt, s.position, ta + s.t * world_per_model);
        return !ff.done();
    });
#else
    struct Window {
        nerf::FieldBatch batch;
        std::vector<Vec3> pos;
        std::vector<float> t, dt, sigma;
    };
    thread_local Window w;
    w.pos.clear();
    w.t.clear();
    w.dt.clear();
    size_t window = 16;
    auto flush = [&] {
        if (w.pos.empty()) return;
        relit_density_batch(field, w.pos, w.sigma, w.batch);
        for (size_t i = 0; i < w.pos.size() && !ff.done(); ++i)
            ff.add(w.sigma[i] * scale * w.dt[i], w.pos[i], ta + w.t[i] * world_per_model);
        w.pos.clear();
        w.t.clear();
        w.dt.clear();
        window = window < 128 ? 2 * window : window;
    };
    nerf::march_ray_visit(mp, n.occupancy, mray, xi, [&](const nerf::MarchSample& s) {
        w.pos.push_back(s.position);
        w.t.push_back(s.t);
        w.dt.push_back(s.dt);
        if (w.pos.size() >= window) flush();
        return !ff.done();
    });
    flush();
#endif
}

// The free flight of the world ray over [0, t_end] through a single relit volume (its cube clips it): what
// integrate_volumes does for one relit volume alone, for tests with analytic fields.
template <class Field>
NPT_HD NPT_INLINE void relit_free_flight(const VolumeView& v, const Field& field, const Ray& ray, float t_end,
                                         float xi, FreeFlight& ff) {
    const Vec3 lo = v.world_to_local.apply(ray.o), ld = v.world_to_local.apply_vector(ray.d);
    float t0, t1;
    if (intersect_box(lo, ld, v.local_min, v.local_max, 0.0f, t_end, &t0, &t1)) march_relit(v, field, ray, t0, t1, xi, ff);
}

NPT_HD NPT_INLINE bool any_relit(Span<const VolumeView> volumes) {
    for (size_t i = 0; i < volumes.size; ++i)
        if (volumes[i].kind == VolumeKind::Nerf && volumes[i].nerf.relit) return true;
    return false;
}

}  // namespace npt::media
