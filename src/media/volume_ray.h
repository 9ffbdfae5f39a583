// A world ray in a volume's spaces: the cube's slab test (local space) and the segment of a NeRF volume as a
// model-space ray. Shared by the emissive integrator (volume_integrator.h), the relit free flight
// (relit_free_flight.h) and the GPU's NeRF pass.
#pragma once

#include <math.h>

#include "core/platform.h"
#include "core/vec.h"
#include "media/volume.h"

namespace npt::media {

// Slab test in the cube's local space; t is shared with world space because the map is affine.
NPT_HD NPT_INLINE bool intersect_box(Vec3 o, Vec3 d, Vec3 lo, Vec3 hi, float tmin, float tmax, float* t0,
                                     float* t1) {
    for (int a = 0; a < 3; ++a) {
        float inv = 1.0f / d[a];
        float ta = (lo[a] - o[a]) * inv, tb = (hi[a] - o[a]) * inv;
        if (ta > tb) {
            float s = ta;
            ta = tb;
            tb = s;
        }
        // NaN (ray parallel to and on a slab plane) leaves the interval unchanged.
        if (ta > tmin) tmin = ta;
        if (tb < tmax) tmax = tb;
        if (tmin > tmax) return false;
    }
    *t0 = tmin;
    *t1 = tmax;
    return tmax > tmin;
}

// The segment [ta, tb] of a world ray through a NeRF volume in model space: a ray from the segment's start with a
// unit direction (*mray) and the segment's length in model units (*t_max), so the march's own box test and t_max
// clip it to [ta, tb]. False for a degenerate or non-finite direction (nothing to march). Shared with the GPU's
// NeRF pass, which gets the segment in this form (render/gpu/wavefront.h).
NPT_HD NPT_INLINE bool nerf_model_segment(const VolumeView& v, const Ray& ray, float ta, float tb, Ray* mray,
                                          float* t_max) {
    const NerfVolumeView& n = v.nerf;
    const Vec3 lo = v.world_to_local.apply(ray.o), ld = v.world_to_local.apply_vector(ray.d);
    const Vec3 om = n.local_to_model.point(lo), dm = n.local_to_model.vector(ld);
    const float len = length(dm);  // model units per unit of t
    if (!(len > 0.0f) || !isfinite(len)) return false;
    const Vec3 dir = dm / len;
    *mray = Ray{om + dir * (ta * len), dir};
    *t_max = (tb - ta) * len;
    return true;
}

}  // namespace npt::media
