// The integrator's entry to lights, shared by CPU and GPU: LightSetView (plain spans built by LightSet on the
// host) and the dispatch that selects a light by power and samples it, plus the pdfs needed for MIS.
#pragma once

#include "core/alias_table.h"
#include "core/platform.h"
#include "core/texture.h"
#include "lights/environment.h"
#include "lights/light_types.h"
#include "lights/punctual.h"
#include "lights/triangle_light.h"

namespace npt::lights {

struct LightSetView {
    Span<const Light> lights;
    AliasTableView selector;                // picks a light proportionally to its power
    Span<const int32_t> mesh_light_offset;  // per scene mesh: index of its triangle 0 in `lights`, or -1
    int32_t environment_light = -1;         // index in `lights`, -1 if the environment is black
    EnvironmentView environment;
    Span<const TextureView> textures;  // scene textures, for textured emitters
};

// Selects a light with u_select (by power) and samples it with u. False when there is nothing to sample or
// the sample carries no light (back face, outside a spot cone, zero-probability texel); *s is then
// unspecified.
NPT_HD NPT_INLINE bool sample_light(const LightSetView& ls, Vec3 ref_p, float u_select, Vec2 u,
                                    LightSample* s) {
    if (ls.selector.bins.empty() || ls.selector.bins.size != ls.lights.size) return false;
    float pmf;
    uint32_t i = ls.selector.sample(u_select, &pmf);
    if (!(pmf > 0.0f)) return false;
    const Light& l = ls.lights[i];
    switch (l.kind) {
        case LightKind::Point:
        case LightKind::Spot:
            if (!sample_point_or_spot(l, ref_p, s)) return false;
            s->pdf = pmf;
            return true;
        case LightKind::Directional:
            if (!sample_directional(l, s)) return false;
            s->pdf = pmf;
            return true;
        case LightKind::Triangle:
            if (!sample_triangle(ls.textures, l, ref_p, u, s)) return false;
            s->pdf *= pmf;
            return true;
        case LightKind::Environment: {
            float pdf;
            if (!environment_sample(ls.environment, u, &s->wi, &s->radiance, &pdf)) return false;
            s->pdf = pdf * pmf;
            s->distance = INFINITY;
            s->is_delta = false;
            return s->pdf > 0.0f;
        }
    }
    return false;
}

// Index in ls.lights of triangle `prim` of `mesh`, or -1 if that triangle does not emit.
NPT_HD NPT_INLINE int32_t triangle_light_index(const LightSetView& ls, uint32_t mesh, uint32_t prim) {
    if (mesh >= ls.mesh_light_offset.size) return -1;
    int32_t first = ls.mesh_light_offset[mesh];
    if (first < 0) return -1;
    size_t i = size_t(first) + prim;
    if (i >= ls.lights.size) return -1;
    const Light& l = ls.lights[i];
    // Guards against a prim index past the end of this mesh's run of triangles.
    if (l.kind != LightKind::Triangle || l.mesh != mesh || l.prim != prim) return -1;
    return int32_t(i);
}

// Solid-angle pdf (incl. selection) with which sample_light would produce point light_p on triangle `prim` of
// `mesh` from ref_p; 0 if that triangle is not an emitter or could not have been sampled from there.
NPT_HD NPT_INLINE float triangle_light_pdf(const LightSetView& ls, uint32_t mesh, uint32_t prim, Vec3 ref_p,
                                           Vec3 light_p) {
    int32_t i = triangle_light_index(ls, mesh, prim);
    if (i < 0 || ls.selector.bins.size != ls.lights.size) return 0.0f;
    return ls.selector.pmf(uint32_t(i)) * triangle_solid_angle_pdf(ls.lights[size_t(i)], ref_p, light_p);
}

// Solid-angle pdf (incl. selection) with which sample_light would produce direction dir towards the
// environment; 0 when there is no environment light.
NPT_HD NPT_INLINE float environment_light_pdf(const LightSetView& ls, Vec3 dir) {
    if (ls.environment_light < 0 || size_t(ls.environment_light) >= ls.lights.size ||
        ls.selector.bins.size != ls.lights.size)
        return 0.0f;
    return ls.selector.pmf(uint32_t(ls.environment_light)) * environment_pdf(ls.environment, dir);
}

// Radiance emitted by triangle light l at barycentrics (b1, b2) towards wo_world (front-face rule).
NPT_HD NPT_INLINE Rgb triangle_emission(const LightSetView& ls, const Light& l, Vec2 bary, Vec3 wo_world) {
    return triangle_emission_at(ls.textures, l, bary, wo_world);
}

}  // namespace npt::lights
