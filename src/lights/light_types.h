// The tagged light record shared by CPU and GPU: one plain struct for every kind, dispatched by a switch on
// `kind` in lights/light.h (pbrt-v4 style, no virtuals). Fields not used by a kind stay at their defaults.
#pragma once

#include <cmath>

#include "core/platform.h"
#include "core/vec.h"

namespace npt::lights {

enum class LightKind : uint8_t { Point, Spot, Directional, Triangle, Environment };

struct Light {
    LightKind kind = LightKind::Point;
    bool two_sided = false;  // triangle: emits from both faces (material double_sided)
    int32_t texture = -1;    // triangle: emissive texture index into LightSetView::textures, -1 if none
    uint32_t mesh = 0;       // triangle: scene mesh index
    uint32_t prim = 0;       // triangle: triangle index within the mesh

    // Point and spot. Intensity is glTF candela taken as W/sr (radiometric, like every other quantity here),
    // so that a punctual light and an emissive surface of equal power look equally bright.
    Vec3 position;
    Vec3 direction{0.0f, 0.0f, -1.0f};  // spot and directional: unit direction the light travels
    Rgb intensity{0.0f};                // point/spot: W/sr; directional: irradiance (lux as W/m^2)
    float cos_inner = 1.0f;             // spot: full intensity inside this cone
    float cos_outer = 0.0f;             // spot: no light outside this cone

    // Triangle, in world space. Barycentrics (b1, b2) weight p1 and p2; p0 gets 1 - b1 - b2.
    Vec3 p0, p1, p2;
    Vec2 uv0, uv1, uv2;
    Vec3 normal;         // unit normalize(cross(p1 - p0, p2 - p0)): the front face
    float area = 0.0f;   // 0 for a degenerate triangle (never sampled)
    Rgb emission{0.0f};  // material emission (factor x strength), multiplied by the texture
};

// What sample_light (lights/light.h) returns.
struct LightSample {
    // Radiance (for delta lights: intensity / d^2, or the illuminance) arriving at ref_p along -wi, NOT
    // divided by pdf.
    Rgb radiance;
    Vec3 wi;         // unit direction from ref_p towards the light
    float distance;  // distance to the sampled light point; INFINITY for directional and environment
    // Solid-angle density INCLUDING the light-selection probability; for delta lights the selection
    // probability alone.
    float pdf;
    bool is_delta;  // point, spot, directional
};

}  // namespace npt::lights
