// Small vector types and their arithmetic, shared by CPU and GPU code. Rgb is a Vec3 of linear radiance.
#pragma once

#include <cmath>

#include "core/platform.h"

namespace npt {

#if !defined(__CUDACC__)
using std::isfinite;
using std::isinf;
using std::isnan;
#endif

constexpr float k_pi = 3.14159265358979323846f;
constexpr float k_inv_pi = 0.31830988618379067154f;
constexpr float k_two_pi = 6.28318530717958647693f;
constexpr float k_inv_2pi = 0.15915494309189533577f;
constexpr float k_inv_4pi = 0.07957747154594766788f;

struct Vec2 {
    float x = 0, y = 0;
    constexpr Vec2() = default;
    NPT_HD NPT_INLINE constexpr Vec2(float x_, float y_) : x(x_), y(y_) {}
    NPT_HD NPT_INLINE Vec2 operator+(Vec2 o) const { return {x + o.x, y + o.y}; }
    NPT_HD NPT_INLINE Vec2 operator-(Vec2 o) const { return {x - o.x, y - o.y}; }
    NPT_HD NPT_INLINE Vec2 operator*(float s) const { return {x * s, y * s}; }
};

struct Vec3 {
    float x = 0, y = 0, z = 0;
    constexpr Vec3() = default;
    NPT_HD NPT_INLINE constexpr explicit Vec3(float s) : x(s), y(s), z(s) {}
    NPT_HD NPT_INLINE constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
    NPT_HD NPT_INLINE float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    NPT_HD NPT_INLINE float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    NPT_HD NPT_INLINE Vec3 operator-() const { return {-x, -y, -z}; }
    NPT_HD NPT_INLINE Vec3 operator+(Vec3 o) const { return {x + o.x, y + o.y, z + o.z}; }
    NPT_HD NPT_INLINE Vec3 operator-(Vec3 o) const { return {x - o.x, y - o.y, z - o.z}; }
    NPT_HD NPT_INLINE Vec3 operator*(Vec3 o) const { return {x * o.x, y * o.y, z * o.z}; }
    NPT_HD NPT_INLINE Vec3 operator/(Vec3 o) const { return {x / o.x, y / o.y, z / o.z}; }
    NPT_HD NPT_INLINE Vec3 operator*(float s) const { return {x * s, y * s, z * s}; }
    NPT_HD NPT_INLINE Vec3 operator/(float s) const { return *this * (1.0f / s); }
    NPT_HD NPT_INLINE Vec3& operator+=(Vec3 o) { x += o.x; y += o.y; z += o.z; return *this; }
    NPT_HD NPT_INLINE Vec3& operator-=(Vec3 o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
    NPT_HD NPT_INLINE Vec3& operator*=(Vec3 o) { x *= o.x; y *= o.y; z *= o.z; return *this; }
    NPT_HD NPT_INLINE Vec3& operator*=(float s) { x *= s; y *= s; z *= s; return *this; }
};
using Rgb = Vec3;

NPT_HD NPT_INLINE Vec3 operator*(float s, Vec3 v) { return v * s; }
NPT_HD NPT_INLINE float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
NPT_HD NPT_INLINE float absdot(Vec3 a, Vec3 b) { return fabsf(dot(a, b)); }
NPT_HD NPT_INLINE Vec3 cross(Vec3 a, Vec3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
NPT_HD NPT_INLINE float length_squared(Vec3 v) { return dot(v, v); }
NPT_HD NPT_INLINE float length(Vec3 v) { return sqrtf(dot(v, v)); }
NPT_HD NPT_INLINE Vec3 normalize(Vec3 v) { return v * (1.0f / length(v)); }
NPT_HD NPT_INLINE Vec3 vmin(Vec3 a, Vec3 b) { return {fminf(a.x, b.x), fminf(a.y, b.y), fminf(a.z, b.z)}; }
NPT_HD NPT_INLINE Vec3 vmax(Vec3 a, Vec3 b) { return {fmaxf(a.x, b.x), fmaxf(a.y, b.y), fmaxf(a.z, b.z)}; }
NPT_HD NPT_INLINE Vec3 vabs(Vec3 a) { return {fabsf(a.x), fabsf(a.y), fabsf(a.z)}; }
NPT_HD NPT_INLINE Vec3 vexp(Vec3 a) { return {expf(a.x), expf(a.y), expf(a.z)}; }
NPT_HD NPT_INLINE float max_component(Vec3 v) { return fmaxf(v.x, fmaxf(v.y, v.z)); }
NPT_HD NPT_INLINE float min_component(Vec3 v) { return fminf(v.x, fminf(v.y, v.z)); }
NPT_HD NPT_INLINE float luminance(Rgb c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }
NPT_HD NPT_INLINE bool is_black(Rgb c) { return c.x == 0.0f && c.y == 0.0f && c.z == 0.0f; }
NPT_HD NPT_INLINE bool is_finite(Vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }
NPT_HD NPT_INLINE Vec3 lerp(float t, Vec3 a, Vec3 b) { return a * (1.0f - t) + b * t; }
NPT_HD NPT_INLINE float clampf(float v, float lo, float hi) { return fminf(fmaxf(v, lo), hi); }
NPT_HD NPT_INLINE float sqr(float v) { return v * v; }
NPT_HD NPT_INLINE float safe_sqrt(float v) { return sqrtf(fmaxf(v, 0.0f)); }

// Reflect wo about n (both pointing away from the surface).
NPT_HD NPT_INLINE Vec3 reflect(Vec3 wo, Vec3 n) { return n * (2.0f * dot(wo, n)) - wo; }

struct Ray {
    Vec3 o;
    Vec3 d;
    NPT_HD NPT_INLINE Vec3 at(float t) const { return o + d * t; }
};

// Orthonormal frame with z = n (Duff et al. 2017, "Building an orthonormal basis, revisited").
struct Frame {
    Vec3 s, t, n;
    NPT_HD NPT_INLINE static Frame from_z(Vec3 n) {
        float sign = copysignf(1.0f, n.z);
        float a = -1.0f / (sign + n.z);
        float b = n.x * n.y * a;
        Frame f;
        f.s = {1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
        f.t = {b, sign + n.y * n.y * a, -n.y};
        f.n = n;
        return f;
    }
    NPT_HD NPT_INLINE Vec3 to_local(Vec3 v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
    NPT_HD NPT_INLINE Vec3 to_world(Vec3 v) const { return s * v.x + t * v.y + n * v.z; }
};

}  // namespace npt
