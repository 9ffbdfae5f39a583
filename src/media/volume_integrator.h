// Emission-absorption along the part of a ray inside the volume cubes and in front of the nearest surface:
//   L = integral of T(t) sigma(t) c(t) dt,   T(t) = exp(-integral of sigma),   over [t_begin, t_end].
// The segment is cut exactly at each cube's faces (oriented boxes, in local space) and at the surface hit,
// split into steps of a quarter voxel along the ray whose lattice starts at a random offset (no striation;
// averaging over the offset converges to the exact integral as the step shrinks), and each step is integrated
// exactly for the field at its midpoint, so a constant medium is exact at any step. Empty space is skipped
// with a coarse majorant grid walked by a 3D DDA. Transmittance is kept in log space; marching stops when T <
// 1e-4.
#pragma once

#include "core/platform.h"
#include "core/srgb.h"
#include "core/vec.h"
#include "media/relit_free_flight.h"
#include "media/volume.h"
#include "media/volume_ray.h"
#if !defined(__CUDACC__)
#include <vector>

#include "nerf/field_batch.h"  // the CPU evaluates NeRF samples in batches
#endif

namespace npt::media {

constexpr float k_log_min_transmittance = -9.2103404f;  // ln(1e-4)
constexpr int k_max_volumes_per_ray = 16;               // further volumes on one ray are ignored

struct VolumeResult {
    Rgb radiance{0.0f};          // emission reaching the segment's start
    float transmittance = 1.0f;  // exp(-optical depth) over the segment; 0 once below 1e-4
};

// A volume as seen by one ray: its index-space line x(t) = xo + t xd and its step.
struct VolumeOnRay {
    const VolumeView* v;
    Vec3 xo, xd;
    float t0, t1;
    float step;
};

struct Accumulator {
    Rgb radiance{0.0f};
    float log_t = 0.0f;
    bool with_emission = true;
    NPT_HD bool done() const { return log_t < k_log_min_transmittance; }
    // Exact for constant sigma and c over the step: T (1 - exp(-sigma len)) c.
    NPT_HD void add(float sigma, Rgb sigma_c_over_sigma, float len) {
        float tau = sigma * len;
        if (!(tau > 0.0f)) return;
        if (with_emission) radiance += sigma_c_over_sigma * (expf(log_t) * -expm1f(-tau));
        log_t -= tau;
    }
};

// Marches one volume over [ta, tb], steps on the lattice ta + (xi + n) * step.
NPT_HD NPT_INLINE void march_one(const VolumeOnRay& r, float ta, float tb, float xi, Accumulator& acc) {
    const VolumeView& v = *r.v;
    float t = ta, next = ta + xi * r.step;
    if (next <= ta) next = ta + r.step;
    while (t < tb && !acc.done()) {
        float te = fminf(next, tb);
        float tm = 0.5f * (t + te);
        FieldSample f = sample_trilinear(v.grid, r.xo + r.xd * tm);
        acc.add(v.density_scale * f.density, f.color * v.emission_scale, te - t);
        t = te;
        next += r.step;
    }
}

// Walks the majorant cells the ray crosses between ta and tb (3D DDA) and marches only the non-empty ones.
NPT_HD NPT_INLINE void march_skipping_empty(const VolumeOnRay& r, float ta, float tb, float xi,
                                            Accumulator& acc) {
    const MajorantView& m = r.v->majorant;
    if (!m.max_density) {
        march_one(r, ta, tb, xi, acc);
        return;
    }
    const float inv_b = 1.0f / float(k_majorant_block);
    // Coarse coordinates u(t) = (x(t) + 1) / B.
    Vec3 uo = (r.xo + Vec3(1.0f)) * inv_b, ud = r.xd * inv_b;
    Vec3 u = uo + ud * ta;
    int cell[3], step[3], n[3] = {m.nx, m.ny, m.nz};
    float t_next[3], t_delta[3];
    for (int a = 0; a < 3; ++a) {
        cell[a] = int(floorf(u[a]));
        if (ud[a] > 0.0f) {
            step[a] = 1;
            t_next[a] = ta + (float(cell[a] + 1) - u[a]) / ud[a];
            t_delta[a] = 1.0f / ud[a];
        } else if (ud[a] < 0.0f) {
            step[a] = -1;
            t_next[a] = ta + (float(cell[a]) - u[a]) / ud[a];
            t_delta[a] = -1.0f / ud[a];
        } else {
            step[a] = 0;
            t_next[a] = INFINITY;
            t_delta[a] = INFINITY;
        }
    }
    float t = ta;
    while (t < tb && !acc.done()) {
        int axis = t_next[0] < t_next[1] ? (t_next[0] < t_next[2] ? 0 : 2) : (t_next[1] < t_next[2] ? 1 : 2);
        float te = fminf(t_next[axis], tb);
        bool inside = cell[0] >= 0 && cell[1] >= 0 && cell[2] >= 0 && cell[0] < n[0] && cell[1] < n[1] &&
                      cell[2] < n[2];
        if (te > t && inside && m.at(cell[0], cell[1], cell[2]) > 0.0f) march_one(r, t, te, xi, acc);
        t = te;
        cell[axis] += step[axis];
        t_next[axis] += t_delta[axis];
        // Leaving the coarse grid in the direction of travel: nothing further along this axis.
        if ((step[axis] > 0 && cell[axis] >= n[axis]) || (step[axis] < 0 && cell[axis] < 0)) break;
    }
}

// Several volumes overlap on [ta, tb]: march them together with the smallest step; the emission of a step is
// shared in proportion to each volume's extinction.
NPT_HD NPT_INLINE void march_overlapping(const VolumeOnRay* rs, const int* active, int n_active, float ta,
                                         float tb, float xi, Accumulator& acc) {
    float step = INFINITY;
    for (int i = 0; i < n_active; ++i) step = fminf(step, rs[active[i]].step);
    float t = ta, next = ta + xi * step;
    if (next <= ta) next = ta + step;
    while (t < tb && !acc.done()) {
        float te = fminf(next, tb);
        float tm = 0.5f * (t + te);
        float sigma = 0.0f;
        Rgb sigma_c(0.0f);
        for (int i = 0; i < n_active; ++i) {
            const VolumeOnRay& r = rs[active[i]];
            FieldSample f = sample_trilinear(r.v->grid, r.xo + r.xd * tm);
            float s = r.v->density_scale * f.density;
            sigma += s;
            sigma_c += f.color * (s * r.v->emission_scale);
        }
        if (sigma > 0.0f) acc.add(sigma, sigma_c / sigma, te - t);
        t = te;
        next += step;
    }
}

// One NeRF sample: sigma (per model unit) scaled by the volume's density scale over the model-space step dt,
// emitting its stored sRGB colour decoded to linear and scaled (nothing for shadow rays). Every sample stands
// for a whole step: with the lattice offset uniform in [0,1) the expected number of samples in a segment of
// length L is L / dt, so the expected optical depth is right at both ends. Shared with the GPU's NeRF pass
// (render/gpu/nerf_segment_kernels.cu).
NPT_HD NPT_INLINE void add_nerf_sample(Accumulator& acc, float sigma, Rgb srgb, float dt, float density_scale,
                                       float emission_scale) {
    const Rgb c = acc.with_emission
                      ? Rgb(srgb_to_linear(srgb.x), srgb_to_linear(srgb.y), srgb_to_linear(srgb.z)) * emission_scale
                      : Rgb(0.0f);
    acc.add(sigma * density_scale, c, dt);
}

// A NeRF volume over [ta, tb] of the world ray: marched in model space through its occupancy grid, each sample
// absorbing with sigma (per model unit, integrated over the model-space step, so the node's scale does not
// change how opaque the object looks) and emitting its colour for the ray's own direction (view-dependent),
// decoded to linear. On the GPU every sample is evaluated alone; on the CPU samples are gathered in windows
// (16, then 32, 64...) and evaluated as one batch (field_batch.h: the MLPs as matrix products), at the price
// of evaluating up to one window past the point where the ray turns opaque.
NPT_HD NPT_INLINE void march_nerf(const VolumeView& v, const Ray& ray, float ta, float tb, float xi,
                                  Accumulator& acc) {
    const NerfVolumeView& n = v.nerf;
    Ray mray;
    nerf::MarchParams mp = n.march;
    if (!nerf_model_segment(v, ray, ta, tb, &mray, &mp.t_max)) return;
    const Vec3 dir = mray.d;
    auto add = [&](float sigma, Rgb srgb, float dt) {
        add_nerf_sample(acc, sigma, srgb, dt, v.density_scale, v.emission_scale);
    };
#if defined(__CUDACC__)  // both nvcc passes: the kernels are per sample
    nerf::march_ray_visit(mp, n.occupancy, mray, xi, [&](const nerf::MarchSample& s) {
        float sigma = 0.0f;
        Rgb rgb(0.0f);
        if (acc.with_emission)
            n.field.query(s.position, dir, &sigma, &rgb);
        else
            sigma = n.field.density(s.position);
        add(sigma, rgb, s.dt);
        return !acc.done();
    });
#else
    struct Window {
        nerf::FieldBatch batch;
        std::vector<Vec3> pos, dirs;
        std::vector<float> dt;
    };
    thread_local Window w;
    w.pos.clear();
    w.dirs.clear();
    w.dt.clear();
    size_t window = 16;
    auto flush = [&] {
        if (w.pos.empty()) return;
        nerf::field_forward(n.field.layout, n.field.params, w.pos.data(), w.dirs.data(), w.pos.size(),
                            acc.with_emission, w.batch);
        for (size_t i = 0; i < w.pos.size() && !acc.done(); ++i)
            add(w.batch.sigma[i], acc.with_emission ? w.batch.rgb[i] : Rgb(0.0f), w.dt[i]);
        w.pos.clear();
        w.dirs.clear();
        w.dt.clear();
        window = window < 128 ? 2 * window : window;
    };
    nerf::march_ray_visit(mp, n.occupancy, mray, xi, [&](const nerf::MarchSample& s) {
        w.pos.push_back(s.position);
        w.dirs.push_back(dir);
        w.dt.push_back(s.dt);
        if (w.pos.size() >= window) flush();
        return !acc.done();
    });
    flush();
#endif
}

// A relit NeRF on [ta, tb] (relit_free_flight.h). Radiance rays with a free flight sample their event there;
// shadow rays (and radiance rays that ask for no event) see its transmittance only. It never emits.
NPT_HD NPT_INLINE void march_relit_nerf(const VolumeView& v, int index, const Ray& ray, float ta, float tb,
                                        float xi, bool shadow, FreeFlight* flight, Accumulator& acc) {
    if (!shadow && flight) {
        march_relit(v, relit_field(v), ray, ta, tb, xi, *flight);
        if (flight->event && flight->volume < 0) flight->volume = index;
        return;
    }
    FreeFlight absorb;  // no target: the optical depth until the accumulator's own cut-off
    absorb.tau_stop = acc.log_t - k_log_min_transmittance;
    march_relit(v, relit_field(v), ray, ta, tb, xi, absorb);
    acc.log_t -= absorb.tau;
}

// Integrates every volume the ray crosses on [t_begin, t_end]. `shadow`: transmittance only, and only volumes
// that cast shadows. `xi` in [0,1) offsets the step lattice. `flight` (radiance rays, optional): the free flight
// through relit NeRFs, whose optical depth it takes instead of the result's transmittance (the path's throughput
// is then the relit volumes' no-event probability times this transmittance); marching stops at its event, with
// the emission of the other volumes up to there.
NPT_HD NPT_INLINE VolumeResult integrate_volumes(Span<const VolumeView> volumes, const Ray& ray,
                                                 float t_begin, float t_end, float xi, bool shadow,
                                                 FreeFlight* flight = nullptr) {
    VolumeResult result;
    VolumeOnRay on_ray[k_max_volumes_per_ray];
    int count = 0;
    for (size_t i = 0; i < volumes.size && count < k_max_volumes_per_ray; ++i) {
        const VolumeView& v = volumes[i];
        if (shadow && !v.casts_shadows) continue;
        Vec3 lo = v.world_to_local.apply(ray.o), ld = v.world_to_local.apply_vector(ray.d);
        float t0, t1;
        if (!intersect_box(lo, ld, v.local_min, v.local_max, t_begin, t_end, &t0, &t1)) continue;
        VolumeOnRay& r = on_ray[count++];
        r.v = &v;
        r.t0 = t0;
        r.t1 = t1;
        if (v.kind == VolumeKind::Nerf) continue;
        r.xo = v.grid.local_to_index.apply(lo);
        r.xd = v.grid.local_to_index.apply_vector(ld);
        float voxels_per_t = length(r.xd);
        r.step = v.step_voxels / fmaxf(voxels_per_t, 1e-20f);
    }
    if (count == 0) return result;

    // Cut [t_begin, t_end] at every entry and exit; each piece is crossed by a fixed set of volumes.
    float bounds[2 * k_max_volumes_per_ray];
    int nb = 0;
    for (int i = 0; i < count; ++i) {
        bounds[nb++] = on_ray[i].t0;
        bounds[nb++] = on_ray[i].t1;
    }
    for (int i = 1; i < nb; ++i)  // insertion sort: nb <= 32
        for (int j = i; j > 0 && bounds[j - 1] > bounds[j]; --j) {
            float s = bounds[j];
            bounds[j] = bounds[j - 1];
            bounds[j - 1] = s;
        }
    Accumulator acc;
    acc.with_emission = !shadow;
    for (int b = 0; b + 1 < nb && !acc.done() && !(flight && flight->event); ++b) {
        float ta = bounds[b], tb = bounds[b + 1];
        if (!(tb > ta)) continue;
        int active[k_max_volumes_per_ray];
        int n_active = 0;
        for (int i = 0; i < count; ++i)
            if (on_ray[i].t0 <= ta && on_ray[i].t1 >= tb) active[n_active++] = i;
        // NeRFs are marched on their own; where one overlaps other volumes, it is composited after them within
        // the piece (an approximation: it does not interleave with them).
        int grids[k_max_volumes_per_ray];
        int n_grids = 0;
        for (int k = 0; k < n_active; ++k)
            if (on_ray[active[k]].v->kind == VolumeKind::Grid) grids[n_grids++] = active[k];
        if (n_grids == 1)
            march_skipping_empty(on_ray[grids[0]], ta, tb, xi, acc);
        else if (n_grids > 1)
            march_overlapping(on_ray, grids, n_grids, ta, tb, xi, acc);
        for (int k = 0; k < n_active && !acc.done() && !(flight && flight->event); ++k) {
            const VolumeView& v = *on_ray[active[k]].v;
            if (v.kind != VolumeKind::Nerf) continue;
            if (v.nerf.relit)
                march_relit_nerf(v, int(&v - volumes.data), ray, ta, tb, xi, shadow, flight, acc);
            else
                march_nerf(v, ray, ta, tb, xi, acc);
        }
    }
    result.radiance = acc.radiance;
    result.transmittance = acc.done() ? 0.0f : expf(acc.log_t);
    return result;
}

}  // namespace npt::media
