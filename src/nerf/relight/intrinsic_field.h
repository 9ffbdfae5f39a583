// The intrinsic fields of a relightable NeRF at one point, NPT_HD for both path tracers: a small hash grid and
// MLP beside the radiance field, giving the diffuse albedo, the roughness and the shading normal that the relit
// renderer shades a scattering event with (a dielectric Principled BSDF: F0 = 0.04, metallic 0). Density still
// comes from the NeRF itself (nerf_field.h); the relight stage (relight_trainer.h) fits these outputs.
#pragma once

#include <math.h>

#include <cstddef>

#include "core/platform.h"
#include "core/vec.h"
#include "materials/bsdf_types.h"
#include "nerf/hash_encoding.h"
#include "nerf/mlp.h"

namespace npt::nerf {

// MLP outputs: 0-2 albedo (sigmoid), 3 roughness (sigmoid, mapped to [k_min_roughness, 1]), 4-6 the normal
// (normalised; the raw vector, so that a zero output is no direction at all).
constexpr int k_intrinsic_outputs = 7;
constexpr float k_min_roughness = 0.05f;

// The diffuse lobe of the shading BSDF (materials/principled.h): `layered` below the specular layer (the models
// of the first relight section, whose header does not say), or `burley`, Cycles' Principled v1 diffuse beside it.
enum class IntrinsicDiffuse : uint8_t { layered, burley };

struct IntrinsicLayout {
    HashGridConfig grid;  // per_level_scale resolved for the model's aabb_scale
    MlpShape mlp;         // inputs: grid.output_dims(); outputs: k_intrinsic_outputs
    size_t mlp_offset = 0, grid_offset = 0, total = 0;
    // As NerfLayout: the grid covers the model's aabb (0.5 -+ aabb_scale / 2).
    Vec3 aabb_min{0.0f, 0.0f, 0.0f};
    float inv_aabb_scale = 1.0f;
    IntrinsicDiffuse diffuse = IntrinsicDiffuse::layered;
    NPT_HD NPT_INLINE Vec3 grid_position(Vec3 p) const { return (p - aabb_min) * inv_aabb_scale; }
};

struct IntrinsicSample {
    Rgb albedo{0.5f};
    float roughness = 0.5f;
    Vec3 normal{0.0f, 0.0f, 1.0f};  // model space, unit length; not yet turned toward the viewer
    IntrinsicDiffuse diffuse = IntrinsicDiffuse::layered;  // the model's, for intrinsic_bsdf
};

NPT_HD NPT_INLINE float intrinsic_sigmoid(float x) { return 1.0f / (1.0f + expf(-x)); }

// The MLP's raw outputs to the sample (shared by the per-point query and the batched trainer).
NPT_HD NPT_INLINE IntrinsicSample intrinsic_from_outputs(const float* out) {
    IntrinsicSample s;
    s.albedo = Rgb(intrinsic_sigmoid(out[0]), intrinsic_sigmoid(out[1]), intrinsic_sigmoid(out[2]));
    s.roughness = k_min_roughness + (1.0f - k_min_roughness) * intrinsic_sigmoid(out[3]);
    const Vec3 n(out[4], out[5], out[6]);
    const float len = sqrtf(n.x * n.x + n.y * n.y + n.z * n.z);
    s.normal = len > 1e-12f ? n * (1.0f / len) : Vec3(0.0f, 0.0f, 1.0f);
    return s;
}

struct IntrinsicFieldView {
    IntrinsicLayout layout;
    const float* params = nullptr;  // nullptr: the model is not relightable
    HashLevels levels;

    IntrinsicFieldView() = default;
    NPT_HD IntrinsicFieldView(const IntrinsicLayout& l, const float* p)
        : layout(l), params(p), levels(hash_levels(l.grid)) {}

    NPT_HD bool valid() const { return params != nullptr; }

    // The fields at a model-space point.
    NPT_HD IntrinsicSample query(Vec3 p) const {
        float enc[k_max_mlp_width], out[k_max_mlp_width];
        for (int i = 0; i < k_intrinsic_outputs; ++i) out[i] = 0.0f;
        hash_encode(layout.grid, levels, params + layout.grid_offset, layout.grid_position(p), enc);
        mlp_forward(layout.mlp, params + layout.mlp_offset, enc, out);
        IntrinsicSample s = intrinsic_from_outputs(out);
        s.diffuse = layout.diffuse;
        return s;
    }
};

// The BSDF a relit scattering event is shaded with: glTF's dielectric metallic-roughness (metallic 0, IOR 1.5,
// so F0 = 0.04) with the sample's albedo as base colour and the model's diffuse lobe: the materials/ Principled
// code evaluates and samples it in the normal's frame.
NPT_HD NPT_INLINE materials::Bsdf intrinsic_bsdf(const IntrinsicSample& s) {
    materials::Bsdf b;
    b.kind = materials::BsdfKind::Principled;
    b.base_color = s.albedo;
    b.metallic = 0.0f;
    b.roughness = s.roughness;
    b.specular = 1.0f;
    b.specular_color = Rgb(1.0f);
    b.transmission = 0.0f;
    b.ior = 1.5f;
    b.burley_diffuse = s.diffuse == IntrinsicDiffuse::burley;
    return b;
}

}  // namespace npt::nerf
