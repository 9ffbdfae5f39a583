// The relight fit's shading without sampling the environment (relight_trainer.h). The fit's K light directions per point
// are spread over the hemisphere, and a glossy lobe (roughness 0.3: a few degrees wide) falls between them, so
// the sampled estimate is almost always zero and rarely huge: the albedo absorbs the reflection of the sky it
// misses (an additive offset: darks too bright) and the roughness drifts to where that estimate is least noisy.
// Instead, the split sum of image-based lighting: the lobe's directional albedo E(mu_o, r), tabulated once from
// the renderer's own BSDF, times the environment prefiltered around the mirror direction with the lobe's width;
// and for the diffuse part its directional albedo times the cosine-prefiltered environment about the normal.
// (The renderer itself is unchanged: it path-traces the fitted fields.)
#pragma once

#include <cstdint>
#include <vector>

#include "core/vec.h"
#include "nerf/relight/intrinsic_field.h"

namespace npt::nerf {

// The directional albedos of intrinsic_bsdf (with the given diffuse lobe) for a view at cosine mu_o to the
// normal, at roughness r: the integral over the hemisphere of cos(theta_i) times its diffuse factor (per unit
// base colour; Burley's depends on the roughness, the layered one does not) and times its specular part.
class DirectionalAlbedoTable {
  public:
    // 32 x 32 entries, 1024 BSDF samples each (fixed seed): tens of milliseconds.
    explicit DirectionalAlbedoTable(IntrinsicDiffuse diffuse);
    float diffuse(float mu_o, float roughness) const;   // bilinear
    float specular(float mu_o, float roughness) const;  // bilinear

  private:
    static constexpr int k_n = 32;
    std::vector<float> m_diffuse;   // [roughness index * k_n + mu index]
    std::vector<float> m_specular;  // [roughness index * k_n + mu index]
};

// The angular width (radians) of the GGX reflection lobe about the mirror direction: alpha sqrt(2 mu_o), the
// spherical-Gaussian fit of the normal distribution (sharpness 2 / alpha^2) warped to reflected directions.
float specular_lobe_width(float roughness, float mu_o);

// An environment of width x height texels (relight_env.h's layout) blurred with spherical Gaussians of a few
// widths: level 0 is the environment itself, level l in [1, k_levels) weights texel u around texel t by
// exp((cos angle(t, u) - 1) / sigma_l^2) times u's solid angle, normalised; plane k_levels is the cosine
// prefilter, sum_u max(0, cos angle(t, u)) L_u omega_u normalised: the irradiance over pi about direction t.
class EnvPrefilter {
  public:
    static constexpr int k_levels = 6;
    static constexpr int k_planes = k_levels + 1;
    EnvPrefilter(int width, int height);
    size_t texels() const { return size_t(m_width) * size_t(m_height); }
    // levels[plane * texels() + t] from env[t].
    void apply(const std::vector<Rgb>& env, std::vector<Rgb>& levels) const;
    // The transpose: d_env[u] += sum over l, t of d_levels[l * texels() + t] * weight_l(t, u).
    void backprop(const std::vector<Rgb>& d_levels, std::vector<Rgb>& d_env) const;
    // Where a lookup at `dir` with lobe width `width` reads: bilinear taps in the two levels about the width,
    // blended linearly in width (clamped to the widest level). Indices into apply()'s `levels`.
    struct Taps {
        uint32_t index[8];
        float weight[8];
    };
    Taps taps(Vec3 dir, float width) const;
    // Bilinear taps of the cosine plane at the normal n.
    struct CosineTaps {
        uint32_t index[4];
        float weight[4];
    };
    CosineTaps cosine_taps(Vec3 n) const;
    static float level_width(int l);

  private:
    struct Entry {
        uint32_t u;
        float w;
    };
    int m_width, m_height;
    std::vector<std::vector<Entry>> m_rows;  // [(plane - 1) * texels() + t]: plane's weights of texel t
    // The transpose, for a parallel backprop: [u] the (row, weight) pairs that read texel u, rows ascending
    // (so each texel sums in the same order as a scatter over the rows would).
    std::vector<std::vector<Entry>> m_columns;
};

}  // namespace npt::nerf
