#include "nerf/relight/specular_prefilter.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "core/rng.h"
#include "materials/bsdf.h"
#include "nerf/relight/intrinsic_field.h"
#include "nerf/relight/relight_env.h"

namespace npt::nerf {

namespace {

constexpr float k_mu_min = 0.01f;  // the table's first column: grazing views

float table_mu(int i, int n) { return k_mu_min + (1.0f - k_mu_min) * float(i) / float(n - 1); }
float table_roughness(int j, int n) { return k_min_roughness + (1.0f - k_min_roughness) * float(j) / float(n - 1); }

// Level widths in radians; the lobe of roughness 1 at normal incidence is 1.41 wide.
constexpr float k_level_width[EnvPrefilter::k_levels] = {0.0f, 0.1f, 0.2f, 0.4f, 0.8f, 1.6f};

}  // namespace

DirectionalAlbedoTable::DirectionalAlbedoTable(IntrinsicDiffuse diffuse)
    : m_diffuse(size_t(k_n) * k_n), m_specular(size_t(k_n) * k_n) {
    constexpr int k_samples = 1024, k_side = 32;  // stratified 32 x 32
    for (int j = 0; j < k_n; ++j) {
        IntrinsicSample one, zero;
        one.roughness = zero.roughness = table_roughness(j, k_n);
        one.albedo = Rgb(1.0f);
        zero.albedo = Rgb(0.0f);
        one.diffuse = zero.diffuse = diffuse;
        const materials::Bsdf b1 = intrinsic_bsdf(one), b0 = intrinsic_bsdf(zero);
        for (int i = 0; i < k_n; ++i) {
            const float mu = table_mu(i, k_n);
            const Vec3 wo(std::sqrt(std::max(0.0f, 1.0f - mu * mu)), 0.0f, mu);
            Pcg32 rng(0x5bec, uint64_t(j * k_n + i));
            double d = 0, e = 0;
            for (int k = 0; k < k_samples; ++k) {
                const Vec2 u((float(k % k_side) + rng.next_float()) / k_side,
                             (float(k / k_side) + rng.next_float()) / k_side);
                // Drawn from the whole BSDF (white base), so that both parts are importance-sampled.
                materials::BsdfSample bs;
                if (!materials::bsdf_sample(b1, wo, rng.next_float(), u, &bs) || bs.wi.z <= 0.0f) continue;
                const float pdf = materials::bsdf_pdf(b1, wo, bs.wi);
                if (!(pdf > 0.0f)) continue;
                const float f1 = materials::bsdf_eval(b1, wo, bs.wi).x, f0 = materials::bsdf_eval(b0, wo, bs.wi).x;
                d += double(f1 - f0) * bs.wi.z / pdf;
                e += double(f0) * bs.wi.z / pdf;
            }
            m_specular[size_t(j) * k_n + size_t(i)] = float(e / k_samples);
            m_diffuse[size_t(j) * k_n + size_t(i)] = float(d / k_samples);
        }
    }
    if (diffuse == IntrinsicDiffuse::layered) {  // the same at every roughness: averaged over them (less noise)
        for (int i = 0; i < k_n; ++i) {
            double mean = 0;
            for (int j = 0; j < k_n; ++j) mean += m_diffuse[size_t(j) * k_n + size_t(i)];
            for (int j = 0; j < k_n; ++j) m_diffuse[size_t(j) * k_n + size_t(i)] = float(mean / k_n);
        }
    }
}

namespace {

// Bilinear in (mu_o, roughness) over a [roughness index * k_n + mu index] table of n x n.
float lookup(const std::vector<float>& table, int n, float mu_o, float roughness) {
    const float x = std::clamp((mu_o - k_mu_min) / (1.0f - k_mu_min), 0.0f, 1.0f) * float(n - 1);
    const float y =
        std::clamp((roughness - k_min_roughness) / (1.0f - k_min_roughness), 0.0f, 1.0f) * float(n - 1);
    const int x0 = std::min(int(x), n - 2), y0 = std::min(int(y), n - 2);
    const float ax = x - float(x0), ay = y - float(y0);
    const auto at = [&](int xi, int yi) { return table[size_t(yi) * size_t(n) + size_t(xi)]; };
    return (1 - ay) * ((1 - ax) * at(x0, y0) + ax * at(x0 + 1, y0)) +
           ay * ((1 - ax) * at(x0, y0 + 1) + ax * at(x0 + 1, y0 + 1));
}

}  // namespace

float DirectionalAlbedoTable::diffuse(float mu_o, float roughness) const {
    return lookup(m_diffuse, k_n, mu_o, roughness);
}

float DirectionalAlbedoTable::specular(float mu_o, float roughness) const {
    return lookup(m_specular, k_n, mu_o, roughness);
}

float specular_lobe_width(float roughness, float mu_o) {
    const float r = std::clamp(roughness, 0.0f, 1.0f);
    return r * r * std::sqrt(2.0f * std::max(mu_o, k_mu_min));
}

float EnvPrefilter::level_width(int l) { return k_level_width[l]; }

EnvPrefilter::EnvPrefilter(int width, int height) : m_width(width), m_height(height) {
    const size_t n = texels();
    std::vector<Vec3> dir(n);
    std::vector<float> omega(n);
    for (int j = 0; j < height; ++j)
        for (int i = 0; i < width; ++i) {
            dir[size_t(j) * width + i] = env_texel_direction(width, height, i, j);
            omega[size_t(j) * width + i] = env_texel_solid_angle(width, height, j);
        }
    m_rows.resize(size_t(k_planes - 1) * n);
    for (int l = 1; l < k_planes; ++l) {
        const bool cosine = l == k_levels;
        const float inv_s2 = cosine ? 0.0f : 1.0f / (k_level_width[l] * k_level_width[l]);
        for (size_t t = 0; t < n; ++t) {
            std::vector<Entry>& row = m_rows[size_t(l - 1) * n + t];
            double total = 0;
            for (size_t u = 0; u < n; ++u) {
                const float c = dot(dir[t], dir[u]);
                const float w = (cosine ? std::max(0.0f, c) : std::exp((c - 1.0f) * inv_s2)) * omega[u];
                total += w;
                row.push_back({uint32_t(u), w});
            }
            // Normalised (the cosine plane too: a uniform sky of 1 gives exactly 1, the continuous integral's
            // value); weights below 1e-5 of the total are dropped (the narrow levels keep a few dozen).
            std::vector<Entry> kept;
            for (const Entry& e : row)
                if (e.w > 1e-5 * total) kept.push_back(e);
            double kept_total = 0;
            for (const Entry& e : kept) kept_total += e.w;
            for (Entry& e : kept) e.w = float(e.w / kept_total);
            row = std::move(kept);
        }
    }
    m_columns.resize(n);
    for (size_t r = 0; r < m_rows.size(); ++r)
        for (const Entry& e : m_rows[r]) m_columns[e.u].push_back({uint32_t(r), e.w});
}

void EnvPrefilter::apply(const std::vector<Rgb>& env, std::vector<Rgb>& levels) const {
    const size_t n = texels();
    levels.assign(size_t(k_planes) * n, Rgb(0.0f));
    std::copy(env.begin(), env.begin() + ptrdiff_t(n), levels.begin());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, m_rows.size(), 64), [&](const tbb::blocked_range<size_t>& b) {
        for (size_t r = b.begin(); r < b.end(); ++r) {
            Rgb sum(0.0f);
            for (const Entry& e : m_rows[r]) sum += env[e.u] * e.w;
            levels[n + r] = sum;
        }
    });
}

void EnvPrefilter::backprop(const std::vector<Rgb>& d_levels, std::vector<Rgb>& d_env) const {
    const size_t n = texels();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16), [&](const tbb::blocked_range<size_t>& b) {
        for (size_t u = b.begin(); u < b.end(); ++u) {
            Rgb sum = d_env[u] + d_levels[u];
            for (const Entry& e : m_columns[u]) sum += d_levels[n + e.u] * e.w;
            d_env[u] = sum;
        }
    });
}

EnvPrefilter::Taps EnvPrefilter::taps(Vec3 dir, float width) const {
    int l0 = k_levels - 2;
    float a = 1.0f;  // weight of level l0 + 1
    for (int l = 0; l + 1 < k_levels; ++l)
        if (width < k_level_width[l + 1]) {
            l0 = l;
            a = std::max(0.0f, (width - k_level_width[l]) / (k_level_width[l + 1] - k_level_width[l]));
            break;
        }
    const EnvTaps b = env_taps(m_width, m_height, dir);
    const size_t n = texels();
    Taps t;
    for (int k = 0; k < 4; ++k) {
        t.index[k] = uint32_t(size_t(l0) * n + size_t(b.index[k]));
        t.weight[k] = (1.0f - a) * b.weight[k];
        t.index[4 + k] = uint32_t(size_t(l0 + 1) * n + size_t(b.index[k]));
        t.weight[4 + k] = a * b.weight[k];
    }
    return t;
}

EnvPrefilter::CosineTaps EnvPrefilter::cosine_taps(Vec3 n) const {
    const EnvTaps b = env_taps(m_width, m_height, n);
    CosineTaps t;
    for (int k = 0; k < 4; ++k) {
        t.index[k] = uint32_t(size_t(k_levels) * texels() + size_t(b.index[k]));
        t.weight[k] = b.weight[k];
    }
    return t;
}

}  // namespace npt::nerf
