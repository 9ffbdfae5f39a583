// The relight stage's fit (nerf/relight/relight_trainer.h) on synthetic surface points whose shading is known
// exactly, to tell what biases its albedo and roughness apart from the NeRF's geometry (docs/benchmarks.md,
// issue 24): 2048 points on a sphere (exact normals, no shadows, no indirect light), a textured albedo, one
// roughness, under a sky like the dev set's capture light (grey above, dark ground, a bright 34-degree emitter at
// 58 degrees elevation) or a uniform white one. The targets integrate sky x BSDF x cosine over the hemisphere
// (48 x 192 directions) with the relit volume's intrinsic_bsdf and either diffuse lobe: `layered` (darkened at
// grazing angles by the specular layer's Fresnel) or `burley` (Cycles 3.4's Principled v1 diffuse: brightened at
// grazing angles on rough surfaces, beside the specular layer: how the dev set's truth was rendered). Each row:
// the fit with one diffuse lobe and one estimator, its relative albedo error after the per-channel scale, and its
// mean roughness.
//   relight_fit_bench [--steps 1500]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/rng.h"
#include "materials/bsdf.h"
#include "nerf/nerf_model.h"
#include "nerf/relight/intrinsic_field.h"
#include "nerf/relight/relight_trainer.h"

using namespace npt;
using namespace npt::nerf;

namespace {

constexpr double k_pi = 3.14159265358979323846;

Rgb true_albedo(Vec3 p) {
    return Rgb(0.2f + 0.3f * (1.0f + std::sin(40.0f * p.x)), 0.5f, 0.5f + 0.3f * std::sin(30.0f * (p.y + p.z)));
}

struct Sky {
    bool emitter = true;
    Vec3 e = normalize(Vec3(std::cos(0.70f) * std::cos(1.01f), std::sin(0.70f) * std::cos(1.01f), std::sin(1.01f)));
    Rgb operator()(Vec3 d) const {
        if (!emitter) return Rgb(1.0f);
        Rgb l = d.z > 0 ? Rgb(0.6f + 0.2f * d.z) : Rgb(0.15f);
        if (dot(d, e) > std::cos(0.30f)) l += Rgb(4.0f, 3.5f, 2.8f);
        return l;
    }
};

RelightSamples sphere_samples(float roughness, IntrinsicDiffuse diffuse, const Sky& sky) {
    constexpr int points = 2048, K = 8, n_theta = 48, n_phi = 192;
    RelightSamples s;
    s.directions = K;
    Pcg32 rng(11, 12);
    auto unit = [&] {
        const float z = 1.0f - 2.0f * rng.next_float(), phi = 6.2831853f * rng.next_float();
        const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
        return Vec3(r * std::cos(phi), r * std::sin(phi), z);
    };
    for (int i = 0; i < points; ++i) {
        const Vec3 n = unit();
        const Vec3 p = Vec3(0.5f) + n * 0.2f;
        Vec3 wo_w = unit();
        if (dot(wo_w, n) < 0.0f) wo_w = -wo_w;
        s.position.push_back(p);
        s.normal.push_back(n);
        s.wo.push_back(wo_w);
        s.image.push_back(uint32_t(i % 2));
        for (int k = 0; k < K; ++k) {
            Vec3 d = unit();
            if (dot(d, n) < 0.0f) d = -d;
            s.dir.push_back(d);
            s.visibility.push_back(1.0f);
            s.indirect.push_back(Rgb(0.0f));
        }
        IntrinsicSample truth;
        truth.albedo = true_albedo(p);
        truth.roughness = roughness;
        truth.diffuse = diffuse;
        const materials::Bsdf b = intrinsic_bsdf(truth);
        const Frame frame = Frame::from_z(n);
        const Vec3 wo = frame.to_local(wo_w);
        Rgb c(0.0f);
        for (int t = 0; t < n_theta; ++t) {
            const double th = (t + 0.5) * 0.5 * k_pi / n_theta;
            const double dw = std::sin(th) * (0.5 * k_pi / n_theta) * (2 * k_pi / n_phi);
            for (int q = 0; q < n_phi; ++q) {
                const double ph = (q + 0.5) * 2 * k_pi / n_phi;
                const Vec3 wi(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)),
                              float(std::cos(th)));
                const Rgb f = materials::bsdf_eval(b, wo, wi);
                c += sky(frame.to_world(wi)) * f * float(wi.z * dw);
            }
        }
        s.target.push_back(c);
    }
    s.lit = s.size();
    return s;
}

NerfModel small_model() {
    NerfModel m;
    m.config.encoding.grid.levels = 2;
    m.config.encoding.grid.log2_table_size = 10;
    m.config.occupancy.resolution = 16;
    m.aabb_scale = 1.0f;
    m.world_to_model = ngp_world_to_model(0.33f, Vec3(0.5f));
    m.params.assign(m.layout().total, 0.01f);
    m.occupancy = OccupancyGrid(1, 16);
    return m;
}

// Relative RMS error of the fitted albedo at every 4th point after the per-channel scale no image can fix.
double relative_albedo_error(const IntrinsicFieldView& view, const RelightSamples& s, double* mean_roughness) {
    double num[3] = {0, 0, 0}, den[3] = {0, 0, 0}, rough = 0;
    std::vector<Rgb> got, want;
    for (size_t i = 0; i < s.size(); i += 4) {
        const IntrinsicSample q = view.query(s.position[i]);
        got.push_back(q.albedo);
        want.push_back(true_albedo(s.position[i]));
        rough += q.roughness;
        for (int c = 0; c < 3; ++c) {
            num[c] += double(got.back()[c]) * want.back()[c];
            den[c] += double(got.back()[c]) * got.back()[c];
        }
    }
    *mean_roughness = rough / double(got.size());
    double err = 0, norm = 0;
    for (size_t i = 0; i < got.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            const double d = got[i][c] * num[c] / den[c] - want[i][c];
            err += d * d;
            norm += double(want[i][c]) * want[i][c];
        }
    return std::sqrt(err / norm);
}

}  // namespace

int main(int argc, char** argv) {
    int steps = 1500;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--steps" && i + 1 < argc) {
            steps = std::atoi(argv[++i]);
        } else {
            std::fprintf(stderr, "usage: relight_fit_bench [--steps N]\n");
            return 2;
        }
    }
    if (steps < 1) {
        std::fprintf(stderr, "relight_fit_bench: --steps must be >= 1\n");
        return 2;
    }
    const auto name = [](IntrinsicDiffuse d) { return d == IntrinsicDiffuse::burley ? "Burley" : "layered"; };
    std::printf("| sky | truth's diffuse | true roughness | fit's diffuse | estimator | albedo error | "
                "mean fitted roughness |\n");
    std::printf("|---|---|---|---|---|---|---|\n");
    for (const bool emitter : {false, true})
        for (const IntrinsicDiffuse truth : {IntrinsicDiffuse::layered, IntrinsicDiffuse::burley})
            for (const float roughness : {0.35f, 0.75f}) {
                Sky sky;
                sky.emitter = emitter;
                const RelightSamples s = sphere_samples(roughness, truth, sky);
                for (const IntrinsicDiffuse lobe : {IntrinsicDiffuse::layered, IntrinsicDiffuse::burley})
                for (const SpecularEstimate est : {SpecularEstimate::sampled, SpecularEstimate::prefiltered}) {
                    RelightTrainSettings ts;
                    ts.intrinsic.grid = {6, 2, 14, 8, 1.5f};
                    ts.intrinsic.finest_resolution = 128.0f;
                    ts.intrinsic.width = 32;
                    ts.intrinsic.hidden_layers = 1;
                    ts.intrinsic.diffuse = lobe;
                    ts.batch = 256;
                    ts.env_width = 32;
                    ts.env_height = 16;
                    ts.learn_exposure = false;
                    ts.specular = est;
                    ts.diffuse = est == SpecularEstimate::prefiltered ? DiffuseEstimate::ratio : DiffuseEstimate::sampled;
                    const NerfModel m = small_model();
                    RelightTrainer tr(m, 2, s, ts);
                    for (int i = 0; i < steps; ++i) tr.step();
                    NerfModel fitted = small_model();
                    fitted.relight = tr.fields(1.0);
                    double rough = 0;
                    const double err = relative_albedo_error(fitted.intrinsic(), s, &rough);
                    std::printf("| %s | %s | %.2f | %s | %s | %.1f%% | %.3f |\n",
                                emitter ? "grey + emitter" : "white", name(truth), roughness, name(lobe),
                                est == SpecularEstimate::prefiltered ? "prefiltered" : "sampled", 100.0 * err, rough);
                    std::fflush(stdout);
                }
            }
    return 0;
}
