// The plain structs every BSDF file and the integrator share: the material parameters (glTF
// metallic-roughness plus KHR_materials_specular/transmission/ior) and one sampled direction. Logic lives in
// bsdf.h.
#pragma once

#include <cstdint>

#include "core/platform.h"
#include "core/vec.h"

namespace npt::materials {

enum class BsdfKind : uint8_t { Lambert, Conductor, Dielectric, Principled };

struct Bsdf {
    BsdfKind kind = BsdfKind::Lambert;
    Rgb base_color{1.0f};  // albedo (Lambert), F0 (Conductor, Schlick), base/transmission tint (others)
    float metallic = 0.0f;
    float roughness = 1.0f;    // glTF perceptual roughness; GGX alpha = roughness^2
    float specular = 1.0f;     // KHR_materials_specular specularFactor
    Rgb specular_color{1.0f};  // KHR_materials_specular specularColorFactor
    float transmission = 0.0f;
    float ior = 1.5f;
    // Principled: the diffuse base as Cycles' Principled v1 (Blender <= 3.x) renders it: Burley's diffuse
    // (brighter at grazing angles on rough surfaces), added beside the specular layer instead of below it.
    bool burley_diffuse = false;
};

// For a delta sample, pdf is the discrete probability of the lobe and f * |wi.z| / pdf is the path weight.
struct BsdfSample {
    Vec3 wi;
    Rgb f;
    float pdf;
    bool is_delta;
};

}  // namespace npt::materials
