#include "nerf_test_scene.h"

#include <nlohmann/json.hpp>
#include <stb_image_write.h>

#include <cmath>
#include <fstream>

#include "core/rng.h"

namespace npt::test {

namespace {

struct Sphere {
    Vec3 center;
    float radius;
    Rgb color;
};

const Sphere k_spheres[] = {
    {{-0.5f, 0.0f, 0.0f}, 0.45f, {0.9f, 0.15f, 0.1f}},
    {{0.5f, 0.2f, 0.0f}, 0.4f, {0.1f, 0.8f, 0.2f}},
    {{0.0f, -0.3f, 0.5f}, 0.35f, {0.15f, 0.3f, 0.95f}},
};

// Colour and coverage of one ray: the nearest sphere, Lambert-shaded from a fixed direction.
bool shade(const Ray& ray, Rgb* out) {
    float best = INFINITY;
    const Vec3 light = normalize(Vec3(1.0f, 1.0f, 2.0f));
    for (const Sphere& s : k_spheres) {
        const Vec3 oc = ray.o - s.center;
        const float b = dot(oc, ray.d), c = dot(oc, oc) - s.radius * s.radius;
        const float disc = b * b - c;
        if (disc < 0) continue;
        const float t = -b - std::sqrt(disc);
        if (t <= 0 || t >= best) continue;
        best = t;
        const Vec3 n = normalize(ray.at(t) - s.center);
        *out = s.color * (0.35f + 0.65f * std::fmax(0.0f, dot(n, light)));
    }
    return best < INFINITY;
}

Mat4 look_at(Vec3 eye, Vec3 target, Vec3 up) {
    const Vec3 f = normalize(target - eye);
    const Vec3 r = normalize(cross(f, up));
    const Vec3 u = cross(r, f);
    Mat4 m;  // columns: right, up, -forward (OpenGL camera), position
    const Vec3 cols[4] = {r, u, -f, eye};
    for (int c = 0; c < 4; ++c)
        for (int a = 0; a < 3; ++a) m.m[a][c] = cols[c][a];
    return m;
}

}  // namespace

nerf::Dataset make_sphere_scene(const SphereSceneOptions& o) {
    nerf::Dataset ds;
    ds.width = ds.height = o.size;
    ds.aabb_scale = 1.0f;
    ds.scale = 0.33f;
    ds.offset = Vec3(0.5f);
    ds.rgba.resize(size_t(o.views) * ds.image_bytes());
    Pcg32 rng(o.view_seed, 7);
    const float focal = 0.5f * float(o.size) / std::tan(0.5f * o.fov_degrees * k_pi / 180.0f);
    for (int v = 0; v < o.views; ++v) {
        // Uniform directions over the sphere, above -0.3 in z so that no camera looks straight up.
        Vec3 dir;
        do {
            const float z = 2.0f * rng.next_float() - 1.0f, phi = 2.0f * k_pi * rng.next_float();
            const float r = std::sqrt(std::fmax(0.0f, 1.0f - z * z));
            dir = Vec3(r * std::cos(phi), r * std::sin(phi), z);
        } while (dir.z < -0.3f || dir.z > 0.9f);
        nerf::Camera cam;
        cam.camera_to_world = look_at(dir * o.distance, Vec3(0.0f), Vec3(0.0f, 0.0f, 1.0f));
        cam.fx = cam.fy = focal;
        cam.cx = cam.cy = 0.5f * float(o.size);
        cam.width = cam.height = o.size;
        ds.cameras.push_back(cam);
        ds.names.push_back("r_" + std::to_string(v));
        uint8_t* img = ds.rgba.data() + size_t(v) * ds.image_bytes();
        for (int y = 0; y < o.size; ++y)
            for (int x = 0; x < o.size; ++x) {
                Rgb sum(0.0f);
                float cover = 0;
                constexpr int k_ss = 4;
                for (int sy = 0; sy < k_ss; ++sy)
                    for (int sx = 0; sx < k_ss; ++sx) {
                        const Ray ray = nerf::generate_pixel_ray(cam, x + (sx + 0.5f) / k_ss,
                                                                 y + (sy + 0.5f) / k_ss);
                        Rgb c;
                        if (shade(ray, &c)) {
                            sum += c;
                            cover += 1.0f;
                        }
                    }
                uint8_t* p = img + (size_t(y) * o.size + x) * 4;
                for (int k = 0; k < 3; ++k)
                    p[k] = cover > 0 ? uint8_t(std::lround(std::fmin(1.0f, sum[k] / cover) * 255.0f)) : 0;
                p[3] = uint8_t(std::lround(cover / (k_ss * k_ss) * 255.0f));
            }
    }
    return ds;
}

void write_dataset(const nerf::Dataset& ds, const std::filesystem::path& folder, float fov_degrees) {
    std::filesystem::create_directories(folder);
    nlohmann::json j;
    j["camera_angle_x"] = fov_degrees * k_pi / 180.0f;
    j["frames"] = nlohmann::json::array();
    for (size_t i = 0; i < ds.cameras.size(); ++i) {
        const std::string name = ds.names[i] + ".png";
        stbi_write_png((folder / name).string().c_str(), ds.width, ds.height, 4, ds.image(i), ds.width * 4);
        nlohmann::json m = nlohmann::json::array();
        for (int r = 0; r < 4; ++r) {
            nlohmann::json row = nlohmann::json::array();
            for (int c = 0; c < 4; ++c) row.push_back(ds.cameras[i].camera_to_world.m[r][c]);
            m.push_back(row);
        }
        j["frames"].push_back({{"file_path", "./" + ds.names[i]}, {"transform_matrix", m}});
    }
    std::ofstream(folder / "transforms.json") << j.dump(2);
}

nerf::NerfConfig small_sphere_config() {
    nerf::NerfConfig c;
    c.encoding.grid.levels = 8;
    c.encoding.grid.log2_table_size = 15;
    c.encoding.finest_resolution = 128.0f;
    c.occupancy.resolution = 32;
    c.occupancy.update_interval = 1;
    c.occupancy.warmup_steps = 8;
    c.training.batch_samples = 1 << 13;
    return c;
}

}  // namespace npt::test
