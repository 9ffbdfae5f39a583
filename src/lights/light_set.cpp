// Builds the light list and its power-proportional selector from a scene. Powers follow pbrt-v4's Phi():
// distant lights (directional, environment) are weighted as if they lit a disk of the scene's bounding
// radius.
#include "lights/light_set.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.h"

namespace npt::lights {

namespace {

double clamped_luminance(Rgb c) { return double(luminance(vmax(c, Rgb(0.0f)))); }

// Weight (power) for the alias table: NaN or negative would make the table throw; such a light gets 0.
double finite_weight(double w) { return std::isfinite(w) && w > 0.0 ? w : 0.0; }

// Radius of the sphere around the bounding box of all geometry (meshes, volume boxes). Distant lights need a
// finite power; with no geometry at all, 1 keeps them selectable.
float bounding_radius(const scene::Scene& scene) {
    Vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
    auto grow = [&](Vec3 p) {
        if (!is_finite(p)) return;
        lo = vmin(lo, p);
        hi = vmax(hi, p);
    };
    for (const auto& mesh : scene.meshes)
        for (Vec3 p : mesh.positions) grow(p);
    for (const auto& vol : scene.volumes)
        for (int c = 0; c < 8; ++c)
            grow(vol.local_to_world.transform_point({(c & 1) ? vol.local_max.x : vol.local_min.x,
                                                     (c & 2) ? vol.local_max.y : vol.local_min.y,
                                                     (c & 4) ? vol.local_max.z : vol.local_min.z}));
    if (!(lo.x <= hi.x)) return 1.0f;
    float r = 0.5f * length(hi - lo);
    return r > 0.0f && std::isfinite(r) ? r : 1.0f;
}

Rgb texture_mean(const TextureView& t) {
    if (!t.valid()) return Rgb(1.0f);
    double sum[3] = {0, 0, 0};
    for (int y = 0; y < t.height; ++y)
        for (int x = 0; x < t.width; ++x) {
            Rgba c = t.texel(x, y);
            sum[0] += c.r;
            sum[1] += c.g;
            sum[2] += c.b;
        }
    double n = double(t.width) * double(t.height);
    return {float(sum[0] / n), float(sum[1] / n), float(sum[2] / n)};
}

}  // namespace

LightSet::LightSet(const scene::Scene& scene) {
    m_scene_radius = bounding_radius(scene);
    const double distant_area = double(k_pi) * double(m_scene_radius) * double(m_scene_radius);

    m_textures.reserve(scene.textures.size());
    for (const auto& t : scene.textures) {
        bool ok = t.width > 0 && t.height > 0 && t.rgba.size() >= size_t(t.width) * size_t(t.height) * 4;
        m_textures.push_back(ok ? TextureView{t.rgba.data(), t.width, t.height} : TextureView{});
    }

    for (const auto& p : scene.lights) {
        Light l;
        l.intensity = vmax(p.intensity, Rgb(0.0f));
        if (!is_finite(l.intensity) || is_black(l.intensity)) continue;
        l.position = p.position;
        float dir_len = length(p.direction);
        l.direction =
            dir_len > 0.0f && std::isfinite(dir_len) ? p.direction / dir_len : Vec3(0.0f, 0.0f, -1.0f);
        double lum = clamped_luminance(l.intensity);
        double power = 0.0;
        switch (p.type) {
            case scene::PunctualType::Point:
                l.kind = LightKind::Point;
                power = 4.0 * double(k_pi) * lum;
                break;
            case scene::PunctualType::Spot:
                l.kind = LightKind::Spot;
                l.cos_outer = std::cos(p.outer_cone);
                // glTF requires inner < outer; a swapped pair would otherwise invert the falloff.
                l.cos_inner = std::max(std::cos(p.inner_cone), l.cos_outer);
                power = 2.0 * double(k_pi) * (1.0 - 0.5 * (double(l.cos_inner) + double(l.cos_outer))) * lum;
                break;
            case scene::PunctualType::Directional:
                l.kind = LightKind::Directional;
                power = distant_area * lum;
                break;
        }
        m_lights.push_back(l);
        m_powers.push_back(finite_weight(power));
    }

    std::vector<Rgb> mean_texture(m_textures.size());
    std::vector<bool> mean_known(m_textures.size(), false);
    m_mesh_light_offset.assign(scene.meshes.size(), -1);
    for (size_t mi = 0; mi < scene.meshes.size(); ++mi) {
        const auto& mesh = scene.meshes[mi];
        if (mesh.material < 0 || size_t(mesh.material) >= scene.materials.size()) continue;
        const auto& mat = scene.materials[size_t(mesh.material)];
        Rgb emission = vmax(mat.emission, Rgb(0.0f));
        if (mat.is_volume || !is_finite(emission) || is_black(emission) || mesh.triangle_count() == 0)
            continue;
        int32_t tex = mat.emissive_texture >= 0 && size_t(mat.emissive_texture) < m_textures.size() &&
                              m_textures[size_t(mat.emissive_texture)].valid()
                          ? mat.emissive_texture
                          : -1;
        Rgb tex_mean(1.0f);
        if (tex >= 0) {
            if (!mean_known[size_t(tex)]) mean_texture[size_t(tex)] = texture_mean(m_textures[size_t(tex)]);
            mean_known[size_t(tex)] = true;
            tex_mean = mean_texture[size_t(tex)];
        }
        double radiant_exitance_lum = clamped_luminance(emission * tex_mean) * double(k_pi);
        if (mat.double_sided) radiant_exitance_lum *= 2.0;

        m_mesh_light_offset[mi] = int32_t(m_lights.size());
        for (size_t t = 0; t < mesh.triangle_count(); ++t) {
            Light l;
            l.kind = LightKind::Triangle;
            l.two_sided = mat.double_sided;
            l.texture = tex;
            l.mesh = uint32_t(mi);
            l.prim = uint32_t(t);
            l.emission = emission;
            uint32_t i0 = mesh.indices[3 * t], i1 = mesh.indices[3 * t + 1], i2 = mesh.indices[3 * t + 2];
            size_t np = mesh.positions.size();
            if (i0 < np && i1 < np && i2 < np) {
                l.p0 = mesh.positions[i0];
                l.p1 = mesh.positions[i1];
                l.p2 = mesh.positions[i2];
                if (mesh.uvs.size() == np) {
                    l.uv0 = mesh.uvs[i0];
                    l.uv1 = mesh.uvs[i1];
                    l.uv2 = mesh.uvs[i2];
                }
                Vec3 c = cross(l.p1 - l.p0, l.p2 - l.p0);
                float len = length(c);
                // A degenerate triangle stays in the list (offsets index triangles by position) with area 0,
                // which the sampler and the pdf treat as "never sampled".
                if (len > 0.0f && std::isfinite(len)) {
                    l.normal = c / len;
                    l.area = 0.5f * len;
                }
            }
            m_lights.push_back(l);
            m_powers.push_back(finite_weight(radiant_exitance_lum * double(l.area)));
            ++m_emissive_triangles;
        }
    }

    const auto& env = scene.environment;
    m_environment.strength = env.strength;
    m_environment.cos_rot = std::cos(env.rotation_y);
    m_environment.sin_rot = std::sin(env.rotation_y);
    m_environment.color = env.color;
    double env_mean_lum = 0.0;
    if (env.texture >= 0) {
        if (size_t(env.texture) >= m_textures.size() || !m_textures[size_t(env.texture)].valid())
            throw Error("scene: environment texture " + std::to_string(env.texture) +
                        " does not exist or has no texels");
        const TextureView& t = m_textures[size_t(env.texture)];
        m_environment.texture = t;
        const int w = t.width, h = t.height;
        // Weight of a texel = mean luminance of the bilinearly filtered map over that texel (the texels
        // around it with quadratic B-spline weights 1/8, 3/4, 1/8, repeat-wrapped as TextureView wraps),
        // times sin(theta) for the equirect Jacobian. It is positive wherever the filtered radiance is.
        std::vector<double> lum(size_t(w) * size_t(h));
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                lum[size_t(y) * size_t(w) + size_t(x)] = clamped_luminance(t.texel(x, y).rgb());
        auto at = [&](int x, int y) {
            x = (x % w + w) % w;
            y = (y % h + h) % h;
            return lum[size_t(y) * size_t(w) + size_t(x)];
        };
        const double k[3] = {0.125, 0.75, 0.125};
        std::vector<double> weight(lum.size());
        double sum_w = 0.0, sum_lum_sin = 0.0, sum_sin = 0.0;
        for (int y = 0; y < h; ++y) {
            double sin_theta = std::sin(double(k_pi) * (y + 0.5) / h);
            for (int x = 0; x < w; ++x) {
                double m = 0.0;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) m += k[dy + 1] * k[dx + 1] * at(x + dx, y + dy);
                weight[size_t(y) * size_t(w) + size_t(x)] = m * sin_theta;
                sum_w += m * sin_theta;
                sum_lum_sin += at(x, y) * sin_theta;
                sum_sin += sin_theta;
            }
        }
        env_mean_lum = sum_lum_sin / sum_sin * double(env.strength);
        if (sum_w > 0.0 && std::isfinite(sum_w) && env.strength > 0.0f) {
            // A floor of 1e-3 of the mean weight: no direction gets zero density from rounding or filtering
            // that the weights above miss, at the cost of 0.1% of the samples.
            double floor = 1e-3 * sum_w / double(weight.size());
            std::vector<float> func(weight.size());
            for (size_t i = 0; i < weight.size(); ++i) {
                int y = int(i / size_t(w));
                func[i] = float(weight[i] + floor * std::sin(double(k_pi) * (y + 0.5) / h));
            }
            m_env_distribution = Distribution2D(func, w, h);
            m_environment.distribution = m_env_distribution.view();
        }
    } else {
        env_mean_lum = clamped_luminance(env.color) * double(env.strength);
    }
    bool env_lights = env_mean_lum > 0.0 && std::isfinite(env_mean_lum) &&
                      (env.texture < 0 || m_environment.distribution.valid());
    if (env_lights) {
        Light l;
        l.kind = LightKind::Environment;
        m_environment_light = int32_t(m_lights.size());
        m_lights.push_back(l);
        // Phi = 4 pi * pi r^2 * mean radiance (pbrt-v4 UniformInfiniteLight / ImageInfiniteLight).
        m_powers.push_back(finite_weight(4.0 * double(k_pi) * distant_area * env_mean_lum));
    }

    m_selector = AliasTable(m_powers);
}

LightSetView LightSet::view() const {
    LightSetView v;
    v.lights = {m_lights.data(), m_lights.size()};
    v.selector = m_selector.view();
    v.mesh_light_offset = {m_mesh_light_offset.data(), m_mesh_light_offset.size()};
    v.environment_light = m_environment_light;
    v.environment = m_environment;
    v.textures = {m_textures.data(), m_textures.size()};
    return v;
}

}  // namespace npt::lights
