// Scenes with closed-form film outputs (alpha, AOVs) for the CPU tests (unit/film_test.cpp) and the OptiX parity
// test (gpu/optix_film_test.cpp): a diffuse sphere under a constant sky, a quad facing the camera, and a constant
// grid volume in front of the quad. Header-only, for tests.
#pragma once

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/srgb.h"
#include "core/transform.h"
#include "scene/scene.h"
#include "scene_builders.h"

namespace npt::test {

// The camera of every film scene: at (0, 0, distance) looking down -z, +y up.
inline scene::Camera film_camera(float distance, float yfov) {
    scene::Camera c;
    c.name = "camera";
    c.position = Vec3(0.0f, 0.0f, distance);
    c.yfov = yfov;
    return c;
}

inline scene::Material film_lambert(Rgb albedo) {
    scene::Material m;
    m.name = "lambert";
    m.base_color = albedo;
    m.metallic = 0.0f;
    m.specular = 0.0f;  // pure Lambert
    return m;
}

// A latitude-longitude sphere of radius 1 at the origin, vertices on the sphere, flat shaded (no normals): it lies
// between the spheres of radius inscribed_radius() and 1.
struct LatLongSphere {
    static constexpr int k_rings = 48, k_segments = 96;
    static scene::Mesh mesh(int material) {
        scene::Mesh m;
        m.name = "sphere";
        m.material = material;
        for (int i = 0; i <= k_rings; ++i)
            for (int j = 0; j <= k_segments; ++j) {
                const float th = float(M_PI) * float(i) / k_rings, ph = 2.0f * float(M_PI) * float(j) / k_segments;
                m.positions.push_back(Vec3(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph)));
            }
        auto at = [](int i, int j) { return uint32_t(i * (k_segments + 1) + j); };
        for (int i = 0; i < k_rings; ++i)
            for (int j = 0; j < k_segments; ++j) {
                // Counter-clockwise seen from outside.
                if (i > 0) m.indices.insert(m.indices.end(), {at(i, j), at(i, j + 1), at(i + 1, j)});
                if (i + 1 < k_rings) m.indices.insert(m.indices.end(), {at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)});
            }
        return m;
    }
    // The least distance from the centre to a face's plane: the sphere of that radius lies inside the mesh.
    static float inscribed_radius(const scene::Mesh& m) {
        float r = 1.0f;
        for (size_t k = 0; k < m.indices.size(); k += 3) {
            const Vec3 a = m.positions[m.indices[k]], b = m.positions[m.indices[k + 1]],
                       c = m.positions[m.indices[k + 2]];
            const Vec3 n = cross(b - a, c - a);
            if (length(n) > 0.0f) r = std::min(r, std::abs(dot(normalize(n), a)));
        }
        return r;
    }
};

// The sphere (base colour `albedo`) under a constant sky of radiance `sky`, seen from z = 4.
inline scene::Scene sphere_under_sky(Rgb albedo, Rgb sky) {
    scene::Scene s;
    s.materials = {film_lambert(albedo)};
    s.meshes = {LatLongSphere::mesh(0)};
    s.environment.color = sky;
    s.cameras = {film_camera(4.0f, 40.0f * float(M_PI) / 180.0f)};
    s.camera = 0;
    return s;
}

// A quad in the plane z = 0 facing the camera at z = 3 (x in [-1, x_right], y in [-1, 1]) under a constant sky.
inline scene::Scene quad_facing_camera(Rgb albedo, float x_right, Rgb sky) {
    scene::Scene s;
    s.materials = {film_lambert(albedo)};
    s.meshes = {make_quad(Vec3(-1.0f, -1.0f, 0.0f), Vec3(x_right + 1.0f, 0.0f, 0.0f), Vec3(0.0f, 2.0f, 0.0f), 0)};
    s.environment.color = sky;
    s.cameras = {film_camera(3.0f, 60.0f * float(M_PI) / 180.0f)};
    s.camera = 0;
    return s;
}

// A cube volume of constant density and colour (an 8^3 instant-ngp raw grid written into `dir`): sigma_ngp 3 over
// a cube of side 2 * half gives sigma = 3 / (2 * half) per world unit. Returns the instance to add to a scene
// whose `source` lies in `dir`.
inline scene::VolumeInstance constant_cube_volume(const std::filesystem::path& dir, Vec3 centre, float half,
                                                  Vec3 srgb) {
    {
        std::ofstream f(dir / "8x8x8_constant.bin", std::ios::binary);
        for (int i = 0; i < 8 * 8 * 8; ++i) {
            const float v[4] = {srgb.x, srgb.y, srgb.z, 3.0f};
            f.write(reinterpret_cast<const char*>(v), sizeof v);
        }
    }
    scene::VolumeInstance v;
    v.name = "volume";
    v.local_to_world = Mat4::translation(centre.x, centre.y, centre.z) * Mat4::scale(half, half, half);
    v.extras_json = R"({"volume": {"file": "8x8x8_constant.bin", "casts_shadows": true}})";
    v.declared_in = dir / "scene.gltf";
    return v;
}

// Where pixel corner (i, j) of a width x height image lies on the image plane at distance 1 (camera.h's mapping).
inline Vec2 image_plane_point(const scene::Camera& c, int width, int height, float i, float j) {
    const float t = std::tan(0.5f * c.yfov), aspect = float(width) / float(height);
    return Vec2((2.0f * i / float(width) - 1.0f) * aspect * t, (1.0f - 2.0f * j / float(height)) * t);
}

}  // namespace npt::test
