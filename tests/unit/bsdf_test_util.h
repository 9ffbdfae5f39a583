// Monte Carlo estimators shared by the materials tests: white furnace, pdf normalisation, and a chi-square
// goodness-of-fit of bsdf_sample against bsdf_pdf (after Mitsuba 3's chi2 tests). Each returns mean and
// standard error so tests can state their tolerance as a number of standard errors.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/rng.h"
#include "core/sampling.h"
#include "materials/bsdf.h"

namespace npt::materials::test {

struct Estimate {
    double mean = 0.0;
    double se = 0.0;  // standard error of the mean
};

inline Vec3 dir_from_cos(float cos_t, float phi = 0.3f) {
    float s = std::sqrt(std::max(0.0f, 1.0f - cos_t * cos_t));
    return {s * std::cos(phi), s * std::sin(phi), cos_t};
}

// E[f |cos| / pdf] over bsdf_sample (channel 0); absorbed samples count 0. With `flux`, transmitted weights
// are multiplied by etap^2 to undo radiance's 1/eta^2, so the result is the fraction of energy kept.
inline Estimate furnace(const Bsdf& b, Vec3 wo, int n, uint64_t seed, bool flux = false) {
    Pcg32 rng(seed, 17);
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < n; ++i) {
        BsdfSample s;
        double w = 0.0;
        float u_lobe = rng.next_float();
        Vec2 u = rng.next_2d();
        if (bsdf_sample(b, wo, u_lobe, u, &s) && s.pdf > 0.0f) {
            w = double(s.f.x) * std::fabs(s.wi.z) / s.pdf;
            if (flux && s.wi.z * wo.z < 0.0f) w *= (wo.z > 0.0f) ? sqr(b.ior) : 1.0 / sqr(b.ior);
        }
        sum += w;
        sum2 += w * w;
    }
    double mean = sum / n;
    double var = std::max(0.0, sum2 / n - mean * mean);
    return {mean, std::sqrt(var / n)};
}

// Integral of bsdf_pdf over the sphere by uniform sphere sampling.
inline Estimate pdf_integral(const Bsdf& b, Vec3 wo, int n, uint64_t seed) {
    Pcg32 rng(seed, 23);
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < n; ++i) {
        Vec3 wi = sample_uniform_sphere(rng.next_2d());
        double v = double(bsdf_pdf(b, wo, wi)) / uniform_sphere_pdf();
        sum += v;
        sum2 += v * v;
    }
    double mean = sum / n;
    return {mean, std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n)};
}

// Probability that bsdf_sample returns a non-delta sample: what bsdf_pdf must integrate to. Samples of
// visible normals whose reflection or refraction lands on the wrong side are discarded, so for GGX lobes this
// is below 1.
inline Estimate non_delta_fraction(const Bsdf& b, Vec3 wo, int n, uint64_t seed) {
    Pcg32 rng(seed, 31);
    int hits = 0;
    for (int i = 0; i < n; ++i) {
        BsdfSample s;
        float u_lobe = rng.next_float();
        Vec2 u = rng.next_2d();
        if (bsdf_sample(b, wo, u_lobe, u, &s) && !s.is_delta) ++hits;
    }
    double p = double(hits) / n;
    return {p, std::sqrt(p * (1.0 - p) / n)};
}

// |pdf integral - sampling success fraction| within 4 combined standard errors of the two MC estimates.
inline void expect_pdf_normalised(const Bsdf& b, Vec3 wo, int n, uint64_t seed) {
    Estimate integral = pdf_integral(b, wo, n, seed);
    Estimate fraction = non_delta_fraction(b, wo, n, seed + 1);
    double tol = 4.0 * std::sqrt(integral.se * integral.se + fraction.se * fraction.se);
    EXPECT_NEAR(integral.mean, fraction.mean, tol) << "wo.z " << wo.z;
    EXPECT_LE(integral.mean, 1.0 + 4.0 * integral.se) << "wo.z " << wo.z;
}

// Upper quantile of the chi-square distribution (Wilson-Hilferty), z = standard normal quantile.
inline double chi2_quantile(int dof, double z) {
    double k = dof, h = 2.0 / (9.0 * k);
    return k * std::pow(1.0 - h + z * std::sqrt(h), 3.0);
}

struct Chi2Result {
    double stat = 0.0;
    int dof = 0;
    double threshold = 0.0;
    int delta_samples = 0;
};

// Histogram of sampled directions over (cos theta, phi) against the pdf integrated per bin (sub-cell midpoint
// rule). Bins with expected count < 5 are pooled into one, as the chi-square approximation requires.
inline Chi2Result chi2_test(const Bsdf& b, Vec3 wo, int n_samples, uint64_t seed) {
    const int n_theta = 16, n_phi = 32, sub = 12;
    std::vector<double> observed(n_theta * n_phi, 0.0), expected(n_theta * n_phi, 0.0);
    Chi2Result r;
    Pcg32 rng(seed, 29);
    for (int i = 0; i < n_samples; ++i) {
        BsdfSample s;
        float u_lobe = rng.next_float();
        Vec2 u = rng.next_2d();
        if (!bsdf_sample(b, wo, u_lobe, u, &s)) continue;
        if (s.is_delta) {
            ++r.delta_samples;
            continue;
        }
        double ct = std::clamp(double(s.wi.z), -1.0, 1.0);
        double phi = std::atan2(double(s.wi.y), double(s.wi.x));
        if (phi < 0) phi += 2.0 * M_PI;
        int it = std::min(n_theta - 1, int((ct + 1.0) * 0.5 * n_theta));
        int ip = std::min(n_phi - 1, int(phi / (2.0 * M_PI) * n_phi));
        observed[it * n_phi + ip] += 1.0;
    }
    for (int it = 0; it < n_theta; ++it)
        for (int ip = 0; ip < n_phi; ++ip) {
            double acc = 0.0;
            for (int a = 0; a < sub; ++a)
                for (int c = 0; c < sub; ++c) {
                    double ct = -1.0 + 2.0 * (it + (a + 0.5) / sub) / n_theta;
                    double phi = 2.0 * M_PI * (ip + (c + 0.5) / sub) / n_phi;
                    double st = std::sqrt(std::max(0.0, 1.0 - ct * ct));
                    Vec3 wi(float(st * std::cos(phi)), float(st * std::sin(phi)), float(ct));
                    acc += bsdf_pdf(b, wo, wi);
                }
            double area = (2.0 / n_theta) * (2.0 * M_PI / n_phi);
            expected[it * n_phi + ip] = acc / (sub * sub) * area * n_samples;
        }
    double pooled_obs = 0.0, pooled_exp = 0.0;
    int bins = 0;
    for (size_t k = 0; k < observed.size(); ++k) {
        if (expected[k] < 5.0) {
            pooled_obs += observed[k];
            pooled_exp += expected[k];
            continue;
        }
        r.stat += (observed[k] - expected[k]) * (observed[k] - expected[k]) / expected[k];
        ++bins;
    }
    if (pooled_exp >= 5.0) {
        r.stat += (pooled_obs - pooled_exp) * (pooled_obs - pooled_exp) / pooled_exp;
        ++bins;
    } else if (pooled_obs > 10.0) {
        r.stat += 1e30;  // samples where the pdf says there are (almost) none
    }
    r.dof = bins - 1;
    // Significance 1e-5 per test (z = 4.265): a handful of chi2 tests over the suite essentially never fail
    // by chance, while a wrong pdf with 10^5 samples gives a statistic many times the threshold.
    r.threshold = chi2_quantile(r.dof, 4.265);
    return r;
}

}  // namespace npt::materials::test
