// Lambertian diffuse reflection: the cheapest lobe, and the diffuse base of the principled material.
// Cosine-weighted sampling makes f * cos / pdf equal to the albedo for every sample.
#pragma once

#include "core/sampling.h"
#include "materials/bsdf_types.h"

namespace npt::materials {

NPT_HD NPT_INLINE Rgb lambert_eval(Rgb albedo, Vec3 wo, Vec3 wi) {
    if (wo.z <= 0.0f || wi.z <= 0.0f) return Rgb(0.0f);
    return albedo * k_inv_pi;
}

NPT_HD NPT_INLINE float lambert_pdf(Vec3 wo, Vec3 wi) {
    if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    return cosine_hemisphere_pdf(wi.z);
}

NPT_HD NPT_INLINE bool lambert_sample(Rgb albedo, Vec3 wo, Vec2 u, BsdfSample* s) {
    if (wo.z <= 0.0f) return false;
    Vec3 wi = sample_cosine_hemisphere(u);
    if (wi.z <= 0.0f) return false;  // the disk's rim maps to grazing directions that carry no energy
    *s = {wi, albedo * k_inv_pi, cosine_hemisphere_pdf(wi.z), false};
    return true;
}

}  // namespace npt::materials
