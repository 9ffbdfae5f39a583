// What the integrator knows about a ray-surface hit: position, normals, uv, the BSDF after texture lookup and
// the emitted radiance. One function for every backend; the backend only supplies the Hit.
#pragma once

#include "core/vec.h"
#include "materials/bsdf.h"
#include "render/scene_view.h"

namespace npt::render {

// A backend's answer to "what does this ray hit first": Embree/OptiX conventions (u, v weight vertices 1 and
// 2).
struct Hit {
    float t = 0.0f;
    uint32_t mesh = 0;
    uint32_t prim = 0;
    float u = 0.0f, v = 0.0f;
};

struct SurfaceInteraction {
    Vec3 p;
    Vec3 ng;        // unit geometric normal of the front face (CCW winding)
    Frame shading;  // z = shading normal; for reflective BSDFs flipped to the side of wo
    Vec2 uv;
    bool front_face;  // the ray arrived on the front side
    materials::Bsdf bsdf;
    Rgb emission;  // radiance emitted towards the ray origin (front face only unless double-sided)
};

NPT_HD NPT_INLINE Rgba lookup(const SceneView& sv, int32_t texture, Vec2 uv) {
    if (texture < 0 || size_t(texture) >= sv.textures.size) return {1.0f, 1.0f, 1.0f, 1.0f};
    return sv.textures[size_t(texture)].sample(uv);
}

NPT_HD NPT_INLINE SurfaceInteraction make_surface_interaction(const SceneView& sv, const Hit& hit,
                                                              const Ray& ray) {
    const MeshView& mesh = sv.meshes[hit.mesh];
    const MaterialView& mat = sv.materials[mesh.material];
    uint32_t i0 = mesh.indices[3 * hit.prim], i1 = mesh.indices[3 * hit.prim + 1],
             i2 = mesh.indices[3 * hit.prim + 2];
    Vec3 p0 = mesh.positions[i0], p1 = mesh.positions[i1], p2 = mesh.positions[i2];
    float b1 = hit.u, b2 = hit.v, b0 = 1.0f - b1 - b2;

    SurfaceInteraction si;
    si.p = p0 * b0 + p1 * b1 + p2 * b2;
    Vec3 e1 = p1 - p0, e2 = p2 - p0;
    si.ng = normalize(cross(e1, e2));
    si.front_face = dot(ray.d, si.ng) < 0.0f;

    Vec2 uv0{0, 0}, uv1{1, 0}, uv2{0, 1};
    if (mesh.uvs) {
        uv0 = mesh.uvs[i0];
        uv1 = mesh.uvs[i1];
        uv2 = mesh.uvs[i2];
    }
    si.uv = uv0 * b0 + uv1 * b1 + uv2 * b2;

    Vec3 ns = si.ng;
    if (mesh.normals) {
        Vec3 n = mesh.normals[i0] * b0 + mesh.normals[i1] * b1 + mesh.normals[i2] * b2;
        float len2 = length_squared(n);
        if (len2 > 0.0f && isfinite(len2)) ns = n * (1.0f / sqrtf(len2));
        if (dot(ns, si.ng) < 0.0f) ns = -ns;  // keep the shading normal on the front side of the triangle
    }

    if (mat.normal_texture >= 0 && mesh.uvs) {
        // Tangent frame from the uv parametrisation; glTF's v runs down the image, so the bitangent follows
        // -dp/dv.
        Vec2 duv1 = uv1 - uv0, duv2 = uv2 - uv0;
        float det = duv1.x * duv2.y - duv1.y * duv2.x;
        if (fabsf(det) > 1e-12f) {
            float inv = 1.0f / det;
            Vec3 dpdu = (e1 * duv2.y - e2 * duv1.y) * inv;
            Vec3 dpdv = (e2 * duv1.x - e1 * duv2.x) * inv;
            Vec3 t = dpdu - ns * dot(ns, dpdu);
            if (length_squared(t) > 0.0f) {
                t = normalize(t);
                Vec3 b = cross(ns, t);
                if (dot(b, dpdv) > 0.0f) b = -b;
                Rgba tex = lookup(sv, mat.normal_texture, si.uv);
                Vec3 nt{(2.0f * tex.r - 1.0f) * mat.normal_scale, (2.0f * tex.g - 1.0f) * mat.normal_scale,
                        2.0f * tex.b - 1.0f};
                Vec3 mapped = t * nt.x + b * nt.y + ns * nt.z;
                if (length_squared(mapped) > 0.0f && dot(mapped, si.ng) > 0.0f) ns = normalize(mapped);
            }
        }
    }

    Rgb base = mat.base_color * lookup(sv, mat.base_color_texture, si.uv).rgb();
    float metallic = mat.metallic, roughness = mat.roughness;
    if (mat.metallic_roughness_texture >= 0) {
        Rgba mr = lookup(sv, mat.metallic_roughness_texture, si.uv);
        roughness *= mr.g;
        metallic *= mr.b;
    }
    si.bsdf = materials::make_bsdf(base, metallic, roughness, mat.specular, mat.specular_color,
                                   mat.transmission, mat.ior);

    // Reflective BSDFs shade both faces alike; transmissive ones need the true front to know inside from
    // outside.
    if (!materials::bsdf_has_transmission(si.bsdf) && !si.front_face) ns = -ns;
    si.shading = Frame::from_z(ns);

    si.emission = Rgb(0.0f);
    if (mat.emits() && (si.front_face || mat.double_sided))
        si.emission = mat.emission * lookup(sv, mat.emissive_texture, si.uv).rgb();
    return si;
}

}  // namespace npt::render
