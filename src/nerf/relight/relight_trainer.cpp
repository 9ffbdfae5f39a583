#include "nerf/relight/relight_trainer.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/error.h"
#include "core/rng.h"
#include "materials/bsdf.h"
#include "nerf/mlp_batch.h"
#include "nerf/relight/relight_env.h"
#include "nerf/relight/specular_prefilter.h"

namespace npt::nerf {

namespace {

constexpr size_t k_points_per_task = 128;            // points per parallel task; gradients summed in chunk order
constexpr float k_roughness_step = 0.01f;  // finite difference of the BSDF in roughness
constexpr float k_prior_roughness = 0.5f;  // where RelightTrainSettings::roughness_prior pulls

OptimizerConfig relight_optimizer(const RelightTrainSettings& settings) {
    OptimizerConfig c;
    c.learning_rate = settings.learning_rate;
    c.decay_start = 1 << 30;  // no decay: the stage is short
    c.ema_decay = settings.average_decay;
    return c;
}

// sRGB encoding of a non-negative linear value and its derivative (the loss is taken where the score is).
inline float srgb_encode(float x, float* d) {
    if (x <= 0.0031308f) {
        *d = 12.92f;
        return 12.92f * std::max(x, 0.0f);
    }
    const float p = std::pow(x, 1.0f / 2.4f);
    *d = 1.055f / 2.4f * p / x;
    return 1.055f * p - 0.055f;
}

inline float sigmoid_grad(float s) { return s * (1.0f - s); }

// The BSDF split as f = base * diffuse + specular for a dielectric Principled lobe (F0 grey): diffuse is the
// colour-independent factor of the base colour, specular the rest.
struct BsdfSplit {
    float diffuse;
    float specular;
};

// The visibility and indirect light the specular lobe about the mirror direction wr sees: the point's own
// directions weighted toward wr with a spherical Gaussian no narrower than 0.6 rad (K directions over a
// hemisphere are ~0.6-0.9 rad apart), so that a narrow lobe still reads the nearest few.
struct LobeLight {
    float visibility = 1.0f;
    Rgb indirect{0.0f};
};

inline LobeLight lobe_light(const RelightSamples& S, const std::vector<uint32_t>& dirs, const float* wk, Vec3 wr,
                            float width) {
    const float s = std::max(width, 0.6f), inv_s2 = 1.0f / (s * s);
    double total = 0, v = 0, plain = 0;
    Rgb ind(0.0f), plain_ind(0.0f);
    int used = 0;
    for (size_t k = 0; k < dirs.size(); ++k) {
        if (wk[k] == 0.0f) continue;  // below the horizon of the shading frame
        const size_t sk = dirs[k];
        const float g = std::exp((dot(S.dir[sk], wr) - 1.0f) * inv_s2);
        total += g;
        v += g * S.visibility[sk];
        ind += S.indirect[sk] * g;
        plain += S.visibility[sk];
        plain_ind += S.indirect[sk];
        ++used;
    }
    LobeLight l;
    if (total > 1e-12) {
        l.visibility = float(v / total);
        l.indirect = ind * float(1.0 / total);
    } else if (used > 0) {
        l.visibility = float(plain / used);
        l.indirect = plain_ind * (1.0f / float(used));
    }
    return l;
}

inline BsdfSplit split_bsdf(float roughness, IntrinsicDiffuse diffuse, Vec3 wo, Vec3 wi) {
    IntrinsicSample s;
    s.roughness = roughness;
    s.diffuse = diffuse;
    s.albedo = Rgb(1.0f);
    const float f1 = materials::bsdf_eval(intrinsic_bsdf(s), wo, wi).x;
    s.albedo = Rgb(0.0f);
    const float f0 = materials::bsdf_eval(intrinsic_bsdf(s), wo, wi).x;
    return {f1 - f0, f0};
}

// places[0..J-1] from places[0], the event draw they lie about: J places on a stratified grid of sample s's
// pixel square, each jittered in its cell, moved along the camera ray onto the plane of the surface through
// the draw (as the pixel's own rays would meet it); not moved where the ray grazes that plane.
void footprint_places(const RelightSamples& S, uint32_t s, size_t J, Pcg32& rng, Vec3* places) {
    const size_t g = J == 9 ? 3 : 2;
    const PixelFootprint& f = S.footprint[s];
    const Vec3 d = -S.wo[s], n = S.normal[S.light_of(s)];
    const float dn = dot(d, n);
    const Vec3 centre = places[0];
    for (size_t j = 0; j < J; ++j) {
        const float x = (float(j % g) + rng.next_float()) / float(g);
        const float y = (float(j / g) + rng.next_float()) / float(g);
        const Vec3 off = f.corner + f.u * x + f.v * y;
        places[j] = centre + off + (std::fabs(dn) > 0.2f ? d * (-dot(off, n) / dn) : Vec3(0.0f));
    }
}

}  // namespace

RelightTrainer::RelightTrainer(const NerfModel& model, size_t image_count, const RelightSamples& samples,
                               const RelightTrainSettings& settings)
    : m_samples(samples),
      m_settings(settings),
      m_layout(make_intrinsic_layout(settings.intrinsic, model.aabb_scale)),
      m_images(image_count),
      m_adam(relight_optimizer(settings), 0, 0, 0) {
    if (samples.size() == 0) throw Error("relight: no surface points to train on");
    if (!(settings.huber_delta >= 0.0f) || !std::isfinite(settings.huber_delta))
        throw Error("relight: the Huber threshold must be finite and >= 0");
    if (settings.env_width < 2 || settings.env_height < 1 || settings.env_width > 4096 ||
        settings.env_height > 4096 || settings.batch < 1)
        throw Error("relight: the environment needs 2x1 to 4096x4096 texels and the batch one point");
    if (!(settings.average_decay >= 0.0f && settings.average_decay < 1.0f))
        throw Error("relight: the parameters' average decay must be in [0, 1)");
    const int fq = settings.footprint_queries;
    static_assert(k_max_footprint_queries == 9, "footprint_places lays 4 or 9 places out");
    if (fq != 1 && fq != 4 && fq != 9) throw Error("relight: footprint queries must be 1, 4 or 9");
    if (fq > 1 && samples.footprint.size() != samples.size())
        throw Error("relight: footprint queries need the samples' pixel squares");
    for (uint32_t img : samples.image)
        if (img >= image_count) throw Error("relight: a point refers to image " + std::to_string(img));
    if (settings.specular == SpecularEstimate::prefiltered || settings.diffuse == DiffuseEstimate::ratio) {
        m_albedo_table = std::make_shared<const DirectionalAlbedoTable>(settings.intrinsic.diffuse);
        IntrinsicSample white;  // the diffuse lobe per unit base colour (Burley's: its roughness set per point)
        white.albedo = Rgb(1.0f);
        white.diffuse = settings.intrinsic.diffuse;
        m_diffuse_lobe = materials::make_principled(intrinsic_bsdf(white));
        m_prefilter = std::make_shared<const EnvPrefilter>(settings.env_width, settings.env_height);
    }
    m_dir_taps.resize(samples.dir.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, samples.dir.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i)
            m_dir_taps[i] = pack_env_taps(settings.env_width, settings.env_height, samples.dir[i]);
    });
    m_env_offset = m_layout.total;
    m_exposure_offset = m_env_offset + size_t(settings.env_width) * settings.env_height * 3;
    m_total = m_exposure_offset + image_count;
    m_params.assign(m_total, 0.0f);
    m_grads.assign(m_total, 0.0f);
    Pcg32 rng(settings.seed, 0x1a7b);
    init_mlp_xavier(m_layout.mlp, m_params.data() + m_layout.mlp_offset, rng);
    for (size_t i = m_layout.grid_offset; i < m_layout.total; ++i)
        m_params[i] = (2.0f * rng.next_float() - 1.0f) * 1e-4f;
    // A uniform grey environment that gives the mean pixel on a mid-grey unshadowed diffuse surface.
    double mean = 0;
    for (const Rgb& t : samples.target) mean += (t.x + t.y + t.z) / 3.0;
    mean /= double(samples.size());
    const float env0 = std::log(float(std::max(mean, 1e-3) / 0.5));
    const float ground = std::log(std::max(settings.ground_share, 1e-6f));
    const Vec3 up = normalize(model.world_to_model.transform_vector(Vec3(0.0f, 0.0f, 1.0f)));
    for (int j = 0; j < settings.env_height; ++j)
        for (int i = 0; i < settings.env_width; ++i) {
            const bool below = dot(env_texel_direction(settings.env_width, settings.env_height, i, j), up) < 0.0f;
            float* texel = &m_params[m_env_offset + (size_t(j) * settings.env_width + size_t(i)) * 3];
            std::fill_n(texel, 3, below ? env0 + ground : env0);
        }
    m_adam = Adam(relight_optimizer(settings), m_total, m_layout.mlp_offset, m_layout.grid_offset);
}

RelightStepStats RelightTrainer::step() {
    const auto t0 = std::chrono::steady_clock::now();
    RelightStepStats stats = compute_gradient();
    m_adam.step(m_params.data(), m_grads.data());
    stats.step = m_adam.state().step;
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return stats;
}

RelightStepStats RelightTrainer::gradient(std::vector<float>& grads) {
    RelightStepStats stats = compute_gradient();
    grads = m_grads;
    return stats;
}

RelightStepStats RelightTrainer::compute_gradient() {
    const RelightSamples& S = m_samples;
    const int W = m_settings.env_width, H = m_settings.env_height;
    const size_t n_env = size_t(W) * H;
    const uint64_t step = m_adam.state().step;
    const size_t batch = size_t(m_settings.batch);
    const float* params = m_params.data();

    const size_t J = size_t(m_settings.footprint_queries);
    std::vector<uint32_t> pick(batch);
    // Where each picked point's fields are queried: one of its event draws, or J places in its pixel's square
    // about that draw ([i * J + j]).
    std::vector<Vec3> at(batch * J);
    Pcg32 rng(mix64(m_settings.seed ^ 0x62617463ULL), step);
    for (size_t i = 0; i < batch; ++i) {
        pick[i] = rng.next_u32() % uint32_t(S.size());
        at[i * J] = S.draw_position(pick[i], rng.next_u32());
        if (J > 1) footprint_places(S, pick[i], J, rng, &at[i * J]);
    }
    std::vector<Rgb> env(n_env);
    for (size_t t = 0; t < n_env; ++t)
        env[t] = Rgb(std::exp(params[m_env_offset + 3 * t]), std::exp(params[m_env_offset + 3 * t + 1]),
                     std::exp(params[m_env_offset + 3 * t + 2]));

    const bool prefiltered = m_prefilter != nullptr;  // either estimate reads the prefiltered environment
    const bool ratio_diffuse = m_settings.diffuse == DiffuseEstimate::ratio;
    const bool lobe_specular = m_settings.specular == SpecularEstimate::prefiltered;
    std::vector<Rgb> env_levels;  // the environment prefiltered for the specular lobes and the cosine
    if (prefiltered) m_prefilter->apply(env, env_levels);

    const int dims = m_layout.grid.output_dims();
    const MlpShape& shape = m_layout.mlp;
    const size_t n_chunks = (batch + k_points_per_task - 1) / k_points_per_task;
    const size_t mlp_params = shape.param_count();
    struct Chunk {
        std::vector<float> enc, out, d_out, d_enc, d_mlp, d_env, d_exposure;
        std::vector<Rgb> d_levels;  // prefiltered: dLoss/d(prefiltered texel), linear radiance
        MlpActivations acts;
        double loss = 0, se = 0, normal_loss = 0, roughness_prior = 0;
    };
    std::vector<Chunk> chunks(n_chunks);
    const HashLevels levels = hash_levels(m_layout.grid);
    const float inv_batch = 1.0f / float(batch);
    const float huber = m_settings.huber_delta;
    const IntrinsicDiffuse diffuse_lobe = m_settings.intrinsic.diffuse;
    const bool burley = diffuse_lobe == IntrinsicDiffuse::burley;  // the diffuse lobe depends on the roughness
    // The ratio estimator's weight of a direction: the diffuse lobe per unit base colour at a roughness.
    const auto diffuse_weight = [&](float rough, Vec3 wo, Vec3 wi) {
        materials::Principled lobe = m_diffuse_lobe;
        if (burley) lobe.burley_roughness = rough;
        return materials::principled_diffuse(lobe, wo, wi).x;
    };

    tbb::parallel_for(size_t(0), n_chunks, [&](size_t c) {
        Chunk& ch = chunks[c];
        const size_t b = c * k_points_per_task, n = std::min(k_points_per_task, batch - b);
        const size_t rows = n * J;
        ch.enc.resize(rows * dims);
        ch.out.resize(rows * k_intrinsic_outputs);
        ch.d_out.assign(rows * k_intrinsic_outputs, 0.0f);
        ch.d_enc.resize(rows * dims);
        ch.d_mlp.assign(mlp_params, 0.0f);
        ch.d_env.assign(n_env * 3, 0.0f);
        ch.d_exposure.assign(m_images, 0.0f);
        if (prefiltered) ch.d_levels.assign(env_levels.size(), Rgb(0.0f));
        for (size_t i = 0; i < rows; ++i)
            hash_encode(m_layout.grid, levels, params + m_layout.grid_offset,
                        m_layout.grid_position(at[b * J + i]), &ch.enc[i * dims]);
        mlp_forward_batch(shape, params + m_layout.mlp_offset, ch.enc.data(), rows, ch.out.data(), &ch.acts);
        std::vector<Rgb> lin;
        std::vector<float> wk, gk;
        std::vector<uint32_t> dirs;  // the [point * K + k] indices of the directions a sample is shaded with
        for (size_t i = 0; i < n; ++i) {
            const uint32_t s = pick[b + i];
            const uint32_t L = S.light_of(s);  // whose normal and light directions (itself unless borrowing)
            S.light_directions(L, dirs);
            const size_t KP = dirs.size();
            lin.resize(KP);
            wk.resize(KP);
            gk.resize(KP);
            const float dir_weight = k_two_pi / float(KP);  // uniform over the hemisphere
            const float* o = &ch.out[i * J * k_intrinsic_outputs];
            float* d_o = &ch.d_out[i * J * k_intrinsic_outputs];
            // The albedo and roughness the pixel sees: the mean over its queries.
            IntrinsicSample q[k_max_footprint_queries];
            for (size_t j = 0; j < J; ++j) q[j] = intrinsic_from_outputs(o + j * k_intrinsic_outputs);
            IntrinsicSample is = q[0];
            for (size_t j = 1; j < J; ++j) {
                is.albedo += q[j].albedo;
                is.roughness += q[j].roughness;
            }
            is.albedo = is.albedo * (1.0f / float(J));
            is.roughness /= float(J);
            // Shaded with the density normal, which the predicted normal learns to follow (its own loss
            // below): the photometric term then has an exact gradient and does not pull the normals toward
            // whatever explains a shadow or a texture.
            const Vec3 wo_w = S.wo[s];
            const Frame frame = Frame::from_z(S.normal[L]);
            const Vec3 wo = frame.to_local(wo_w);
            const float r = is.roughness;
            const float r2 = r + k_roughness_step <= 1.0f ? r + k_roughness_step : r - k_roughness_step;
            const float dr = r2 - r;
            Rgb acc_d(0.0f), acc_s(0.0f), acc_d2(0.0f), acc_s2(0.0f);
            // DiffuseEstimate::ratio: the diffuse part is a ratio estimator: the unshadowed diffuse light, E_d(mu_o) times
            // the cosine-prefiltered environment at n (no sampling noise), times the share of it the point's
            // directions find unshadowed, num / den (exactly 1 where nothing is in the way); plus their
            // indirect light. (On the glossy test sphere the directions' own sum left 24% albedo error, this 5%.)
            Rgb num(0.0f), den(0.0f), indirect_d(0.0f);
            Rgb num2(0.0f), den2(0.0f), indirect_d2(0.0f);  // at r2, for Burley's roughness-dependent lobe
            for (size_t k = 0; k < KP; ++k) {
                const size_t sk = dirs[k];
                const Vec3 wi = frame.to_local(S.dir[sk]);
                wk[k] = 0.0f;
                if (wi.z <= 0.0f || wo.z <= 0.0f) continue;
                const EnvTaps taps = unpack_env_taps(W, H, m_dir_taps[sk]);
                Rgb le(0.0f);
                for (int j = 0; j < 4; ++j) le += env[taps.index[j]] * taps.weight[j];
                lin[k] = le * S.visibility[sk] + S.indirect[sk];
                const float w = dir_weight * wi.z;
                wk[k] = w;
                if (ratio_diffuse) {
                    const float g = diffuse_weight(r, wo, wi) * w;
                    gk[k] = g;
                    num += le * (S.visibility[sk] * g);
                    den += le * g;
                    indirect_d += S.indirect[sk] * g;
                    if (burley) {
                        const float g2 = diffuse_weight(r2, wo, wi) * w;
                        num2 += le * (S.visibility[sk] * g2);
                        den2 += le * g2;
                        indirect_d2 += S.indirect[sk] * g2;
                    }
                }
                if (ratio_diffuse && lobe_specular) continue;
                const BsdfSplit f = split_bsdf(r, diffuse_lobe, wo, wi), f2 = split_bsdf(r2, diffuse_lobe, wo, wi);
                if (!ratio_diffuse) {
                    acc_d += lin[k] * (f.diffuse * w);
                    acc_d2 += lin[k] * (f2.diffuse * w);
                }
                if (!lobe_specular) {
                    acc_s += lin[k] * (f.specular * w);
                    acc_s2 += lin[k] * (f2.specular * w);
                }
            }
            Rgb ratio(1.0f), unshadowed(0.0f);
            EnvPrefilter::CosineTaps cos_taps{};
            float e_diffuse = 0.0f;
            // The specular part: the split sum E_s(mu_o, r) (V L_r + R) about the mirror direction.
            EnvPrefilter::Taps spec_taps{};
            float spec_scale = 0.0f;  // dC_specular / dL_prefiltered
            if (ratio_diffuse && wo.z > 0.0f) {
                e_diffuse = m_albedo_table->diffuse(wo.z, r);
                cos_taps = m_prefilter->cosine_taps(S.normal[L]);
                Rgb lc(0.0f);
                for (int j = 0; j < 4; ++j) lc += env_levels[cos_taps.index[j]] * cos_taps.weight[j];
                unshadowed = lc * e_diffuse;
                for (int ch3 = 0; ch3 < 3; ++ch3)
                    if (den[ch3] > 0.0f) ratio[ch3] = num[ch3] / den[ch3];
                acc_d = unshadowed * ratio + indirect_d;
                acc_d2 = acc_d;  // the layered diffuse factor does not depend on the roughness
                if (burley) {
                    Rgb ratio2(1.0f);
                    for (int ch3 = 0; ch3 < 3; ++ch3)
                        if (den2[ch3] > 0.0f) ratio2[ch3] = num2[ch3] / den2[ch3];
                    acc_d2 = lc * m_albedo_table->diffuse(wo.z, r2) * ratio2 + indirect_d2;
                }
            }
            if (lobe_specular && wo.z > 0.0f) {
                const Vec3 wr = S.normal[L] * (2.0f * wo.z) - wo_w;
                const auto lobe = [&](float rough, EnvPrefilter::Taps* taps, float* scale) {
                    const float width = specular_lobe_width(rough, wo.z);
                    const LobeLight ll = lobe_light(S, dirs, wk.data(), wr, width);
                    *taps = m_prefilter->taps(wr, width);
                    Rgb lr(0.0f);
                    for (int j = 0; j < 8; ++j) lr += env_levels[taps->index[j]] * taps->weight[j];
                    const float e_spec = m_albedo_table->specular(wo.z, rough);
                    *scale = e_spec * ll.visibility;
                    return lr * *scale + ll.indirect * e_spec;
                };
                EnvPrefilter::Taps unused;
                float unused_scale;
                acc_s = lobe(r, &spec_taps, &spec_scale);
                acc_s2 = lobe(r2, &unused, &unused_scale);
            }
            const float e = std::exp(params[m_exposure_offset + S.image[s]]);
            Rgb d_c;  // dLoss/dC
            double se = 0, loss = 0;
            Rgb pred;
            for (int ch3 = 0; ch3 < 3; ++ch3) {
                pred[ch3] = e * (is.albedo[ch3] * acc_d[ch3] + acc_s[ch3]);
                float dp, dt;
                const float diff = srgb_encode(pred[ch3], &dp) - srgb_encode(S.target[s][ch3], &dt);
                se += double(diff) * diff;
                float d_loss = diff;  // d loss / d diff
                if (huber > 0.0f && std::fabs(diff) > huber) {
                    d_loss = std::copysign(huber, diff);
                    loss += double(huber) * (std::fabs(diff) - 0.5 * huber);
                } else {
                    loss += 0.5 * double(diff) * diff;
                }
                d_c[ch3] = d_loss * dp * inv_batch;
            }
            ch.loss += loss;
            ch.se += se;
            // Albedo and roughness.
            float d_r = 0.0f, d_e = 0.0f;
            Rgb d_albedo;  // dLoss / d(the mean albedo)
            for (int ch3 = 0; ch3 < 3; ++ch3) {
                d_albedo[ch3] = d_c[ch3] * e * acc_d[ch3];
                d_r += d_c[ch3] * e *
                       (is.albedo[ch3] * (acc_d2[ch3] - acc_d[ch3]) + (acc_s2[ch3] - acc_s[ch3])) / dr;
                d_e += d_c[ch3] * pred[ch3];  // dC/d(log e) = C
            }
            // The roughness prior: where the capture light says little about the roughness, it stays near
            // k_prior_roughness instead of drifting.
            const float dev = r - k_prior_roughness;
            ch.roughness_prior += double(m_settings.roughness_prior) * dev * dev;
            d_r += 2.0f * m_settings.roughness_prior * dev * inv_batch;
            // Through the mean to each query's sigmoids.
            for (size_t j = 0; j < J; ++j) {
                float* d_q = d_o + j * k_intrinsic_outputs;
                for (int ch3 = 0; ch3 < 3; ++ch3)
                    d_q[ch3] = d_albedo[ch3] * sigmoid_grad(q[j].albedo[ch3]) / float(J);
                const float sr = (q[j].roughness - k_min_roughness) / (1.0f - k_min_roughness);
                d_q[3] = d_r * (1.0f - k_min_roughness) * sigmoid_grad(sr) / float(J);
            }
            ch.d_exposure[S.image[s]] += d_e;
            // The environment: the prefiltered texels the lobes read, then the texels each direction read
            // (env = exp(parameter): d_env is in parameter space, d_levels in radiance).
            if (prefiltered && wo.z > 0.0f) {
                for (int ch3 = 0; ch3 < 3; ++ch3) {
                    const float g_d = d_c[ch3] * e * is.albedo[ch3];  // dLoss / d acc_d
                    if (ratio_diffuse)
                        for (int j = 0; j < 4; ++j)
                            ch.d_levels[cos_taps.index[j]][ch3] +=
                                g_d * ratio[ch3] * e_diffuse * cos_taps.weight[j];
                    if (lobe_specular && spec_scale > 0.0f)
                        for (int j = 0; j < 8; ++j)
                            ch.d_levels[spec_taps.index[j]][ch3] +=
                                d_c[ch3] * e * spec_scale * spec_taps.weight[j];
                }
            }
            for (size_t k = 0; k < KP; ++k) {
                if (wk[k] == 0.0f) continue;
                const size_t sk = dirs[k];
                const EnvTaps taps = unpack_env_taps(W, H, m_dir_taps[sk]);
                Rgb d_le(0.0f);  // dLoss / d(the environment's radiance toward direction k)
                if (ratio_diffuse) {
                    // d ratio / d le_k = g_k (V_k - ratio) / den
                    for (int ch3 = 0; ch3 < 3; ++ch3)
                        d_le[ch3] = den[ch3] > 0.0f ? d_c[ch3] * e * is.albedo[ch3] * unshadowed[ch3] * gk[k] *
                                                          (S.visibility[sk] - ratio[ch3]) / den[ch3]
                                                    : 0.0f;
                }
                if ((!ratio_diffuse || !lobe_specular) && S.visibility[sk] > 0.0f) {
                    const BsdfSplit f = split_bsdf(r, diffuse_lobe, wo, frame.to_local(S.dir[sk]));
                    const float f_d = ratio_diffuse ? 0.0f : f.diffuse, f_s = lobe_specular ? 0.0f : f.specular;
                    for (int ch3 = 0; ch3 < 3; ++ch3)
                        d_le[ch3] += d_c[ch3] * e * (is.albedo[ch3] * f_d + f_s) * wk[k] * S.visibility[sk];
                }
                for (int ch3 = 0; ch3 < 3; ++ch3)
                    for (int j = 0; j < 4; ++j)
                        ch.d_env[size_t(taps.index[j]) * 3 + ch3] +=
                            d_le[ch3] * taps.weight[j] * env[taps.index[j]][ch3];
            }
            // The normal output follows the density normal, at each query.
            for (size_t j = 0; j < J; ++j) {
                const float* oj = o + j * k_intrinsic_outputs;
                float* d_q = d_o + j * k_intrinsic_outputs;
                const Vec3 raw(oj[4], oj[5], oj[6]);
                const float len = std::max(length(raw), 1e-6f);
                const Vec3 nh = raw / len;
                const Vec3 diff = nh - S.normal[L];
                ch.normal_loss += dot(diff, diff) / float(J);
                const Vec3 d_nh = diff * (2.0f * m_settings.normal_weight * inv_batch / float(J));
                const Vec3 d_raw = (d_nh - nh * dot(nh, d_nh)) / len;
                d_q[4] = d_raw.x;
                d_q[5] = d_raw.y;
                d_q[6] = d_raw.z;
            }
        }
        mlp_backward_batch(shape, params + m_layout.mlp_offset, ch.enc.data(), ch.acts, ch.d_out.data(),
                           ch.d_mlp.data(), ch.d_enc.data());
    });

    float* grads = m_grads.data();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, m_grads.size(), size_t(1) << 16),
                      [&](const tbb::blocked_range<size_t>& r) { std::fill(grads + r.begin(), grads + r.end(), 0.0f); });
    // The hash grid's gradient: each level's entries are its own, so the levels run in parallel, each summing
    // over the batch's points in order (the same sums as one pass over the points).
    tbb::parallel_for(0, m_layout.grid.levels, [&](int l) {
        for (size_t c = 0; c < n_chunks; ++c) {
            const size_t b = c * k_points_per_task, n = std::min(k_points_per_task, batch - b);
            for (size_t i = 0; i < n * J; ++i)
                hash_level_backward(m_layout.grid, levels.level[l], l, m_layout.grid_position(at[b * J + i]),
                                    &chunks[c].d_enc[i * dims], grads + m_layout.grid_offset);
        }
    });
    RelightStepStats stats;
    double prior = 0;  // the priors' part of the objective
    for (size_t c = 0; c < n_chunks; ++c) {
        const Chunk& ch = chunks[c];
        for (size_t i = 0; i < mlp_params; ++i) grads[m_layout.mlp_offset + i] += ch.d_mlp[i];
        for (size_t i = 0; i < n_env * 3; ++i) grads[m_env_offset + i] += ch.d_env[i];
        if (m_settings.learn_exposure)
            for (size_t i = 0; i < m_images; ++i) grads[m_exposure_offset + i] += ch.d_exposure[i];
        stats.loss += ch.loss;
        stats.mse += ch.se;
        stats.normal_loss += ch.normal_loss;
        prior += ch.roughness_prior / double(batch);
    }
    if (prefiltered) {  // through the prefilter to the texels, then through env = exp(parameter)
        std::vector<Rgb> d_levels(env_levels.size(), Rgb(0.0f)), d_env(n_env, Rgb(0.0f));
        for (const Chunk& ch : chunks)
            for (size_t i = 0; i < d_levels.size(); ++i) d_levels[i] += ch.d_levels[i];
        m_prefilter->backprop(d_levels, d_env);
        for (size_t t = 0; t < n_env; ++t)
            for (int c = 0; c < 3; ++c) grads[m_env_offset + 3 * t + size_t(c)] += d_env[t][c] * env[t][c];
    }
    // Priors: a grey mean environment, exposures around 1.
    double mean_log[3] = {0, 0, 0};
    for (size_t t = 0; t < n_env; ++t)
        for (int c = 0; c < 3; ++c) mean_log[c] += params[m_env_offset + 3 * t + c];
    for (double& m : mean_log) m /= double(n_env);
    const double grey = (mean_log[0] + mean_log[1] + mean_log[2]) / 3.0;
    for (size_t t = 0; t < n_env; ++t)
        for (int c = 0; c < 3; ++c)
            grads[m_env_offset + 3 * t + c] +=
                float(2.0 * m_settings.grey_weight * (mean_log[c] - grey) / n_env);
    for (int c = 0; c < 3; ++c) prior += m_settings.grey_weight * (mean_log[c] - grey) * (mean_log[c] - grey);
    if (m_settings.learn_exposure)
        for (size_t i = 0; i < m_images; ++i) {
            const float le = params[m_exposure_offset + i];
            grads[m_exposure_offset + i] += 2.0f * m_settings.exposure_weight * le / float(m_images);
            prior += m_settings.exposure_weight * double(le) * le / double(m_images);
        }
    stats.step = m_adam.state().step;
    stats.loss /= double(batch);
    stats.mse /= 3.0 * double(batch);
    stats.normal_loss /= double(batch);
    stats.objective = stats.loss + m_settings.normal_weight * stats.normal_loss + prior;
    return stats;
}

RelightFields RelightTrainer::fields(double seconds) const {
    std::vector<float> avg(m_total);
    m_adam.averaged_params(m_params.data(), avg.data());
    RelightFields f;
    f.config = m_settings.intrinsic;
    f.params.assign(avg.begin(), avg.begin() + m_layout.total);
    f.capture_env.width = m_settings.env_width;
    f.capture_env.height = m_settings.env_height;
    const size_t n_env = size_t(m_settings.env_width) * m_settings.env_height;
    f.capture_env.texels.resize(n_env);
    for (size_t t = 0; t < n_env; ++t)
        f.capture_env.texels[t] =
            Rgb(std::exp(avg[m_env_offset + 3 * t]), std::exp(avg[m_env_offset + 3 * t + 1]),
                std::exp(avg[m_env_offset + 3 * t + 2]));
    f.exposure.resize(m_images);
    for (size_t i = 0; i < m_images; ++i) f.exposure[i] = Rgb(std::exp(avg[m_exposure_offset + i]));
    f.steps = steps_done();
    f.seconds = seconds;
    return f;
}

}  // namespace npt::nerf
