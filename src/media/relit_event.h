// A scattering event in a relit NeRF, as the path tracer shades it: the world point, the shading frame of the
// intrinsic normal carried into world space and turned toward the viewer, and the spawn point its shadow and
// continuation rays start from (nerf/relight/relit_spawn.h). NPT_HD.
#pragma once

#include <math.h>

#include "core/platform.h"
#include "core/vec.h"
#include "media/relit_free_flight.h"
#include "media/volume.h"
#include "nerf/relight/intrinsic_field.h"
#include "nerf/relight/relit_spawn.h"

namespace npt::media {

struct RelitEvent {
    Vec3 p{0.0f};       // the event's world point
    Vec3 origin{0.0f};  // where its rays start: the spawn point, in world space
    Frame frame;        // shading frame; frame.n is the unit world normal facing the incoming ray's origin
    nerf::IntrinsicSample sample;  // albedo and roughness; its normal in model space, facing
};

// m^T v for the linear part of an affine map.
NPT_HD NPT_INLINE Vec3 apply_transpose(const Affine3& a, Vec3 v) {
    return {a.m[0] * v.x + a.m[3] * v.y + a.m[6] * v.z, a.m[1] * v.x + a.m[4] * v.y + a.m[7] * v.z,
            a.m[2] * v.x + a.m[5] * v.y + a.m[8] * v.z};
}

// m^-1 v for the linear part of an affine map (Cramer's rule; the cube's map is invertible by construction).
NPT_HD NPT_INLINE Vec3 apply_inverse(const Affine3& a, Vec3 v) {
    const float* m = a.m;
    const Vec3 c0(m[0], m[3], m[6]), c1(m[1], m[4], m[7]), c2(m[2], m[5], m[8]);
    const float det = dot(c0, cross(c1, c2));
    return Vec3(dot(v, cross(c1, c2)), dot(c0, cross(v, c2)), dot(c0, cross(c1, v))) / det;
}

// The event at distance t along the world ray, model-space sample position p_model, with the intrinsic fields
// `s` there. With A the world -> model linear map (local -> model after world -> local), normals map by the
// inverse transpose of model -> world, i.e. n_world ~ A^T n_model; a model-space displacement dp maps to
// A^-1 dp, which lies on the facing side of the world tangent plane (dot(A^-1 n, A^T n) = |n|^2 > 0): the
// spawn point is moved in model space (where the offset is defined, in march steps) and mapped back.
NPT_HD NPT_INLINE RelitEvent make_relit_event(const VolumeView& v, const Ray& ray, float t, Vec3 p_model,
                                              nerf::IntrinsicSample s) {
    const nerf::LocalToModel& l2m = v.nerf.local_to_model;
    const Vec3 d_model = l2m.vector(v.world_to_local.apply_vector(ray.d));
    // Facing in model space is facing in world space: dot(A^T n, d) = dot(n, A d).
    const Vec3 n_model = nerf::relit_facing_normal(s.normal, d_model);
    Vec3 n_world = apply_transpose(v.world_to_local, l2m.transpose_vector(n_model));
    const float len = length(n_world);
    n_world = len > 0.0f && isfinite(len) ? n_world / len : -ray.d;
    if (dot(n_world, ray.d) > 0.0f) n_world = -n_world;  // rounding at grazing angles
    const Vec3 dp_model = nerf::relit_spawn_point(p_model, n_model, v.nerf.march.min_step) - p_model;
    const Vec3 dp_world = apply_inverse(v.world_to_local, l2m.inverse_vector(dp_model));
    RelitEvent e;
    e.p = ray.at(t);
    e.origin = e.p + dp_world;
    e.frame = Frame::from_z(n_world);
    s.normal = n_model;
    e.sample = s;
    return e;
}

// The event a free flight found along `ray` in one of `volumes` (a relit NeRF: its intrinsic fields queried
// at the event's sample position).
NPT_HD NPT_INLINE RelitEvent relit_event_at(Span<const VolumeView> volumes, const Ray& ray, const FreeFlight& f) {
    const VolumeView& v = volumes[size_t(f.volume)];
    return make_relit_event(v, ray, f.t, f.p_model, v.nerf.intrinsic.query(f.p_model));
}

}  // namespace npt::media
