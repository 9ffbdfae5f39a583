#include "nerf/relight/surface_normals.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "nerf/relight/wavefront_march.h"

namespace npt::nerf {

namespace {

constexpr float k_min_alpha = 0.5f;       // a stencil ray that is more transparent than this saw no surface
constexpr float k_max_stretch = 8.0f;     // the stencil's two arms differ more than this: it straddles an edge
constexpr float k_min_facing = 0.05f;     // |cos| to the view below this: the plane is edge-on, an edge again

// A cell of the smoothing's spatial hash: integer coordinates packed into one sortable key.
uint64_t cell_key(int x, int y, int z) {
    constexpr int64_t bias = 1 << 20;
    return (uint64_t(x + bias) << 42) | (uint64_t(y + bias) << 21) | uint64_t(z + bias);
}

}  // namespace

std::vector<Vec3> smooth_normals(const std::vector<Vec3>& points, const std::vector<Vec3>& normals, float radius) {
    if (!(radius > 0.0f) || points.empty()) return normals;
    const float inv_cell = 1.0f / radius;
    auto cell_of = [&](Vec3 p, int a) { return int(std::floor(p[a] * inv_cell)); };
    // Points sorted by cell, so that a cell's points are one run found by binary search.
    std::vector<std::pair<uint64_t, uint32_t>> order(points.size());
    for (size_t i = 0; i < points.size(); ++i)
        order[i] = {cell_key(cell_of(points[i], 0), cell_of(points[i], 1), cell_of(points[i], 2)), uint32_t(i)};
    std::sort(order.begin(), order.end());
    const float inv_two_sigma2 = 1.0f / (2.0f * 0.25f * radius * radius);
    std::vector<Vec3> out(normals.size());
    tbb::parallel_for(size_t(0), points.size(), [&](size_t i) {
        const Vec3 ni = normals[i];
        if (!(dot(ni, ni) > 0.0f)) {
            out[i] = ni;
            return;
        }
        const int cx = cell_of(points[i], 0), cy = cell_of(points[i], 1), cz = cell_of(points[i], 2);
        Vec3 sum(0.0f);
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const uint64_t key = cell_key(cx + dx, cy + dy, cz + dz);
                    auto it = std::lower_bound(order.begin(), order.end(), std::make_pair(key, uint32_t(0)));
                    for (; it != order.end() && it->first == key; ++it) {
                        const Vec3 d = points[it->second] - points[i];
                        const float d2 = dot(d, d);
                        if (d2 > radius * radius) continue;
                        const float agree = std::max(0.0f, dot(ni, normals[it->second]));
                        const float a2 = agree * agree;
                        sum += normals[it->second] * (std::exp(-d2 * inv_two_sigma2) * a2 * a2);
                    }
                }
        const float len = length(sum);
        out[i] = len > 0.0f ? sum / len : ni;
    });
    return out;
}

std::vector<Vec3> density_normals(FieldQuery& query, const std::vector<Vec3>& points,
                                  const std::vector<Vec3>& toward, float step) {
    std::vector<Vec3> probes;
    probes.reserve(points.size() * 6);
    for (const Vec3& p : points)
        for (int a = 0; a < 3; ++a) {
            Vec3 e(0.0f);
            e[a] = step;
            probes.push_back(p + e);
            probes.push_back(p - e);
        }
    std::vector<float> sigma(probes.size());
    if (!probes.empty()) query.evaluate(probes.data(), nullptr, probes.size(), sigma.data(), nullptr);
    std::vector<Vec3> normals(points.size(), Vec3(0.0f));
    for (size_t i = 0; i < points.size(); ++i) {
        Vec3 g;
        for (int a = 0; a < 3; ++a)
            g[a] = std::log(std::max(sigma[6 * i + 2 * a], 1e-6f)) - std::log(std::max(sigma[6 * i + 2 * a + 1], 1e-6f));
        const float len = length(g);
        if (!(len > 0.0f) || !std::isfinite(len)) continue;
        Vec3 n = -g / len;
        if (dot(n, toward[i]) < 0.0f) n = -n;
        normals[i] = n;
    }
    return normals;
}

std::vector<Vec3> depth_stencil_normals(const NerfModel& model, FieldQuery& query,
                                        const std::vector<Camera>& cameras, const std::vector<PixelRef>& pixels,
                                        float half_width) {
    static constexpr float offsets[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
    const Mat4& w2m = model.world_to_model;
    std::vector<WaveRay> rays(pixels.size() * 4);
    std::vector<Vec3> view(pixels.size());
    for (size_t i = 0; i < pixels.size(); ++i) {
        const PixelRef& p = pixels[i];
        const Camera& cam = cameras.at(p.camera);
        for (int k = 0; k < 4; ++k) {
            const Ray world = generate_pixel_ray(cam, p.px + offsets[k][0] * half_width, p.py + offsets[k][1] * half_width);
            WaveRay& r = rays[4 * i + k];
            r.ray = Ray{w2m.transform_point(world.o), normalize(w2m.transform_vector(world.d))};
            r.jitter = p.jitter;
        }
        const Ray centre = generate_pixel_ray(cam, p.px, p.py);
        view[i] = -normalize(w2m.transform_vector(centre.d));
    }
    march_wavefront(model, query, rays, WaveMode::depth);
    std::vector<Vec3> normals(pixels.size(), Vec3(0.0f));
    for (size_t i = 0; i < pixels.size(); ++i) {
        Vec3 end[4];
        bool ok = true;
        for (int k = 0; k < 4 && ok; ++k) {
            const WaveRay& r = rays[4 * i + k];
            const float alpha = 1.0f - r.transmittance;
            ok = alpha >= k_min_alpha;
            if (ok) end[k] = r.ray.o + r.ray.d * (r.depth / alpha);
        }
        if (!ok) continue;
        const Vec3 ex = end[0] - end[1], ey = end[2] - end[3];
        const float lx = length(ex), ly = length(ey);
        if (!(lx > 0.0f && ly > 0.0f) || std::max(lx, ly) > k_max_stretch * std::min(lx, ly)) continue;
        const Vec3 c = cross(ex, ey);
        const float lc = length(c);
        if (!(lc > 0.0f) || !std::isfinite(lc)) continue;
        Vec3 n = c / lc;
        float facing = dot(n, view[i]);
        if (facing < 0.0f) {
            n = -n;
            facing = -facing;
        }
        if (facing < k_min_facing) continue;
        normals[i] = n;
    }
    return normals;
}

}  // namespace npt::nerf
