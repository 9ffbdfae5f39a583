// What the relit-medium tests share: analytic fields (density and intrinsic fields in model space), a volume
// view for them, a relightable NerfModel made in code, and a path loop that drives the renderer's free flight
// and event shading (media/relit_free_flight.h, render/path_integrator.h relit_scatter) through one analytic
// relit volume in a scene without surfaces. Header-only, for tests.
#pragma once

#include <cmath>
#include <random>

#include "core/rng.h"
#include "core/transform.h"
#include "materials/bsdf.h"
#include "media/placement.h"
#include "media/relit_event.h"
#include "nerf/nerf_model.h"
#include "render/path_integrator.h"

namespace npt::test {

// Up to two balls of constant density (model space); the normal is the radial direction of the ball the point
// is nearest to (by signed distance), so a dense ball looks like a sphere with exact normals.
struct BallsField {
    Vec3 centre[2] = {Vec3(0.5f), Vec3(0.5f)};
    float radius[2] = {0.35f, 0.0f};
    int count = 1;
    float sigma = 50.0f;  // per model unit
    Rgb albedo{1.0f};
    float roughness = 0.5f;

    int nearest(Vec3 p) const {
        int best = 0;
        for (int i = 1; i < count; ++i)
            if (length(p - centre[i]) - radius[i] < length(p - centre[best]) - radius[best]) best = i;
        return best;
    }
    float density(Vec3 p) const {
        for (int i = 0; i < count; ++i)
            if (length(p - centre[i]) < radius[i]) return sigma;
        return 0.0f;
    }
    nerf::IntrinsicSample intrinsic(Vec3 p) const {
        nerf::IntrinsicSample s;
        s.albedo = albedo;
        s.roughness = roughness;
        const Vec3 r = p - centre[nearest(p)];
        s.normal = length(r) > 0.0f ? normalize(r) : Vec3(0.0f, 0.0f, 1.0f);
        return s;
    }
};

// A NeRF volume view for an analytic field: the cube [-1, 1]^3 placed by local_to_world, model space [0, 1]^3,
// no occupancy grid (every cell occupied), the default march (steps of sqrt(3)/1024 model units).
inline media::VolumeView analytic_view(const Mat4& local_to_world) {
    media::VolumeView v;
    v.kind = media::VolumeKind::Nerf;
    v.nerf.relit = true;
    v.nerf.local_to_model = nerf::local_to_model(Vec3(-1.0f), Vec3(1.0f), nerf::CropBox{});
    v.world_to_local = media::affine_from(local_to_world.inverse());
    return v;
}

// A tracer for scenes without surfaces.
struct NoSurfaces {
    bool intersect(const Ray&, float, render::Hit*) const { return false; }
    bool occluded(const Ray&, float) const { return false; }
};

// The transmittance of the field along [0, tmax] of `ray`, as shadow rays see it (T < 1e-4 counts as 0).
template <class Field>
float relit_transmittance(const media::VolumeView& v, const Field& field, const Ray& ray, float tmax, float xi) {
    media::FreeFlight f;
    f.tau_stop = -media::k_log_min_transmittance;
    media::relit_free_flight(v, field, ray, tmax, xi, f);
    return f.done() ? 0.0f : std::exp(-f.tau);
}

// trace_path (render/path_integrator.h) for a scene whose only volume is the analytic relit field and which has
// no surfaces: the same free flight, event and light/BSDF sampling code, with the field's own intrinsic query.
// `absorbed` (optional) receives, per path, the sum over its events of throughput x (1 - w), w the weight of an
// independent BSDF sample at the event from `loss_rng`: an unbiased estimate of the energy the BSDF absorbs
// along the path (see the furnace test).
template <class Field, class Sampler>
Rgb trace_relit(const render::SceneView& sv, const media::VolumeView& v, const Field& field, Ray ray,
                Sampler& sampler, const render::PathSettings& ps, Pcg32* loss_rng = nullptr, Rgb* absorbed = nullptr) {
    render::PathState st;
    st.prev_p = ray.o;
    const NoSurfaces tracer;
    if (absorbed) *absorbed = Rgb(0.0f);
    for (;;) {
        media::FreeFlight flight;
        const float xi = sampler.next_1d();
        flight.target = media::free_flight_target(sampler.next_1d());
        media::relit_free_flight(v, field, ray, INFINITY, xi, flight);
        render::ShadowRequest shadow;
        Ray next;
        bool more;
        if (flight.event) {
            const media::RelitEvent ev =
                media::make_relit_event(v, ray, flight.t, flight.p_model, field.intrinsic(flight.p_model));
            if (absorbed && st.depth < ps.max_depth) {
                const materials::Bsdf b = nerf::intrinsic_bsdf(ev.sample);
                materials::BsdfSample bs;
                const float u_lobe = loss_rng->next_float();
                Rgb w(0.0f);
                if (materials::bsdf_sample(b, ev.frame.to_local(-ray.d), u_lobe, loss_rng->next_2d(), &bs) &&
                    bs.pdf > 0.0f)
                    w = bs.f * (std::fabs(bs.wi.z) / bs.pdf);
                *absorbed += st.throughput * (Rgb(1.0f) - w);
            }
            more = render::relit_scatter(sv, tracer, st, ev, -ray.d, sampler, ps, &shadow, &next);
        } else {
            render::Hit hit;
            more = render::path_scatter(sv, tracer, st, ray, false, hit, sampler, ps, &shadow, &next);
        }
        if (shadow.pending)
            st.radiance += shadow.contribution * relit_transmittance(v, field, shadow.ray, shadow.tmax, shadow.xi);
        if (!more) break;
        ray = next;
    }
    return st.radiance;
}

// A small NeRF with random density features and a relight section with random intrinsic parameters: a
// relightable model as the renderer sees one, before any relight training exists. `pass_network`: the NeRF's
// hash grid of the default shape (16 levels x 2 features, 2^14 entries), the one the OptiX wavefront form's fp16
// kernels take (nerf/cuda/fused_mlp.h mlp_shape_supported), instead of 4 levels (quicker on the CPU).
inline nerf::NerfModel random_relightable_model(uint32_t seed, bool relightable = true, bool pass_network = false) {
    nerf::NerfConfig c;
    if (pass_network) {
        c.encoding.grid.log2_table_size = 14;
    } else {
        c.encoding.grid.levels = 4;
        c.encoding.grid.log2_table_size = 12;
    }
    c.encoding.finest_resolution = 64;
    c.occupancy.resolution = 16;
    c.march.max_steps = 256;  // steps of sqrt(3)/256: fewer samples, the tests stay quick
    nerf::NerfModel m = nerf::create_model(c, 1.0f, nerf::ngp_world_to_model(0.33f, Vec3(0.5f)));
    std::mt19937 g(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const nerf::NerfLayout layout = m.layout();
    for (size_t i = layout.grid_offset; i < layout.total; ++i) m.params[i] = 2.0f * u(g);
    m.training.reset();
    if (!relightable) return m;
    nerf::RelightFields r;
    r.config.grid = nerf::HashGridConfig{3, 2, 10, 4, 1.5f};
    r.config.finest_resolution = 32.0f;
    r.config.width = 16;
    r.config.hidden_layers = 1;
    r.params.resize(nerf::make_intrinsic_layout(r.config, m.aabb_scale).total);
    for (float& p : r.params) p = u(g);
    m.relight = std::move(r);
    return m;
}

}  // namespace npt::test
