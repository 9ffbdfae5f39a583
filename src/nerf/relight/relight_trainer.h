// The relight stage: fits the intrinsic fields (albedo, roughness, normal: intrinsic_field.h), the capture
// environment and an exposure per image to the training pixels, with the trained NeRF's density fixed. For
// each point of RelightSamples the predicted colour is
//   C = e_image * [(2 pi / K) sum_k (V_k L_env(w_k) + R_k) a f_d(r, n; w_o, w_k) max(0, n . w_k) + S]
// (Monte Carlo over the hemisphere with the precomputed visibility V and the NeRF's indirect light R; the K
// directions are the point's own and its pooled neighbours': RelightSamples::light_directions), with a f_d
// + f_s the relit renderer's BSDF (intrinsic_bsdf, with the settings' diffuse lobe: Burley's depends on r) in
// the frame of the density normal n, and S its specular part; a and r are the means over the places the
// point's pixel is queried at (RelightTrainSettings::footprint_queries). With SpecularEstimate::prefiltered
// (the default, specular_prefilter.h) S is the split sum E_s(mu_o, r) (V_r L_r + R_r) about the mirror
// direction, L_r the environment prefiltered with the lobe's width; with SpecularEstimate::sampled the same
// sum over the K directions with f_s. The diffuse part is a ratio estimator (DiffuseEstimate::ratio, the
// default: the cosine-prefiltered unshadowed light times the share the K directions find unshadowed, exact
// where nothing is in the way) or the sum over the K directions (DiffuseEstimate::sampled). Compared with the
// pixel in sRGB (squared error). The normal output learns the density normal by its own loss: the renderer
// shades with it. Albedo against light has a per-channel scale no image can fix: the prior is an environment
// whose mean is grey (equal mean log radiance in R, G and B), and exposures whose mean log is 0.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "materials/principled.h"
#include "nerf/adam.h"
#include "nerf/nerf_model.h"
#include "nerf/relight/relight_env.h"
#include "nerf/relight/relight_samples.h"

namespace npt::nerf {

class DirectionalAlbedoTable;
class EnvPrefilter;

// How the fit estimates its shading (the comment at the top): `sampled`, sums over each point's K directions
// (which miss glossy lobes); `prefiltered`, prefiltered environments (specular_prefilter.h).
enum class SpecularEstimate { prefiltered, sampled };
// How the fit estimates the diffuse light: `sampled`, the sum over each point's K directions; `ratio`, the
// unshadowed light from the prefiltered environment times the share of it the K directions find unshadowed.
enum class DiffuseEstimate { ratio, sampled };

constexpr int k_max_footprint_queries = 9;  // RelightTrainSettings::footprint_queries: 1, 4 or 9

struct RelightTrainSettings {
    IntrinsicConfig intrinsic;
    int env_width = 32, env_height = 16;
    int batch = 1024;               // points per step
    float learning_rate = 1e-2f;
    // The fields the stage delivers are the moving average of its parameters over the steps, weighted by this
    // factor per step: 0.99 averages over the last ~100 steps, 0.95 (tiny-cuda-nn's, the NeRF trainer's) over
    // ~20. A parameter is set by the few batches that reach its hash entries, each moving it by about the
    // learning rate (Adam's steps do not shrink with the gradient), so the last steps' noise stays in it
    // unless many are averaged: 0.99 gave +0.25 dB of albedo and 0.2 degrees of normal on the CPU's dev model
    // over three seeds (docs/benchmarks.md, "the fields' average").
    float average_decay = 0.99f;
    float normal_weight = 0.3f;     // weight of |n_pred - n_density|^2 against the photometric loss
    float grey_weight = 1.0f;       // the grey-environment prior
    // The environment's texels below the training world's horizon (+z up, as `poses` and NeRF-synthetic write
    // it) start at this share of those above: the ground reflects part of the sky's light (a ground of albedo
    // ~0.1, asphalt to grass). The images constrain the environment's vertical profile weakly (an up-facing
    // surface's brighter albedo explains its pixels as well as a brighter sky), so where they leave it free the
    // start stays: with a start as bright as the sky (1) dev's albedo came out ~18% too bright on up-facing
    // surfaces against side-facing ones; 0.1 gave +0.5 dB of albedo on the CPU and on a GPU, 0.3 +0.3 / +0.4
    // (docs/benchmarks.md, "the albedo against the normal").
    float ground_share = 0.1f;
    float exposure_weight = 0.1f;   // pulls log exposures toward 0
    // Pulls each point's roughness toward 0.5: weight of (r - 0.5)^2 per point against the photometric loss.
    // A smooth capture light constrains the roughness little, and the fit, left free, used low roughness to
    // turn the environment into a view-dependent texture (sparkling highlights under a small sun).
    float roughness_prior = 0.0f;
    // The photometric loss per channel of the sRGB residual d: d^2 / 2 (0, the default), or Huber's with this
    // threshold (linear beyond it): each point's albedo then follows the median of its views more than their
    // mean, so a highlight that the fit's shading cannot explain, seen from a few views, moves it less.
    float huber_delta = 0.0f;
    // Where each point's fields are queried: 1, at one event draw on its camera ray; N = 4 or 9, averaged
    // over a 2x2 or 3x3 stratified grid of its pixel's square (RelightSamples::footprint), moved along the
    // ray onto the surface's plane. A photo's pixel averages the object over that square: fitted at one place
    // per pixel, the albedo is that average, blurred by the square once more when a camera renders it.
    int footprint_queries = 1;
    bool learn_exposure = true;
    SpecularEstimate specular = SpecularEstimate::prefiltered;  // measured on dev: docs/benchmarks.md
    DiffuseEstimate diffuse = DiffuseEstimate::ratio;
    uint64_t seed = 7;
};

struct RelightStepStats {
    uint64_t step = 0;
    double loss = 0;          // photometric loss per point (sRGB; squared or Huber's: huber_delta)
    double mse = 0;           // per channel, sRGB, for a PSNR
    double normal_loss = 0;   // mean |n_pred - n_density|^2
    double objective = 0;     // what the gradient is of: photometric + weighted normal loss + priors
    double seconds = 0;
};

class RelightTrainer {
  public:
    RelightTrainer(const NerfModel& model, size_t image_count, const RelightSamples& samples,
                   const RelightTrainSettings& settings);
    RelightStepStats step();
    uint64_t steps_done() const { return m_adam.state().step; }
    // The gradient step() would apply next (the same batch), into grads; nothing changes. For tests.
    RelightStepStats gradient(std::vector<float>& grads);
    // The raw parameters: the intrinsic network, then log radiance of the environment's texels (RGB), then the
    // log exposure of each image. For tests (finite differences).
    std::vector<float>& raw_params() { return m_params; }
    const IntrinsicLayout& layout() const { return m_layout; }
    size_t environment_offset() const { return m_env_offset; }
    size_t exposure_offset() const { return m_exposure_offset; }
    // The averaged parameters, the environment and the exposures as the model's relight section.
    RelightFields fields(double seconds) const;

  private:
    RelightStepStats compute_gradient();  // into m_grads, for the batch of the current step

    const RelightSamples& m_samples;
    RelightTrainSettings m_settings;
    IntrinsicLayout m_layout;
    size_t m_env_offset = 0, m_exposure_offset = 0, m_total = 0;
    size_t m_images = 0;
    std::vector<float> m_params, m_grads;
    std::vector<PackedEnvTaps> m_dir_taps;  // per light direction of the samples: its environment lookup
    Adam m_adam;
    // With SpecularEstimate::prefiltered or DiffuseEstimate::ratio.
    std::shared_ptr<const DirectionalAlbedoTable> m_albedo_table;
    std::shared_ptr<const EnvPrefilter> m_prefilter;
    materials::Principled m_diffuse_lobe;  // DiffuseEstimate::ratio: its principled_diffuse is the ratio's weight
};

}  // namespace npt::nerf
