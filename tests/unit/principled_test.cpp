#include "materials/principled.h"

#include <gtest/gtest.h>

#include "bsdf_test_util.h"

namespace npt::materials {
namespace {

Bsdf principled(Rgb base, float metallic, float roughness, float transmission, float specular = 1.0f) {
    Bsdf b = make_bsdf(base, metallic, roughness, specular, Rgb(1.0f), transmission, 1.5f);
    EXPECT_EQ(b.kind, BsdfKind::Principled);
    return b;
}

TEST(Principled, WhiteFurnaceDoesNotGainEnergyAndMetalConserves) {
    uint64_t seed = 100;
    for (float roughness : {0.0f, 0.3f, 0.7f, 1.0f}) {
        for (float metallic : {0.0f, 0.5f}) {
            for (float transmission : {0.0f, 0.5f}) {
                Bsdf b = principled(Rgb(1.0f), metallic, roughness, transmission);
                for (float cz : {1.0f, 0.5f, 0.1f}) {
                    auto e = test::furnace(b, test::dir_from_cos(cz), 60000, ++seed, /*flux=*/true);
                    // 4 standard errors of the MC mean over 6e4 samples.
                    EXPECT_LE(e.mean, 1.0 + 4.0 * e.se)
                        << "r " << roughness << " m " << metallic << " t " << transmission << " cos " << cz;
                }
            }
        }
    }
}

TEST(Principled, WhiteMetalConservesEnergy) {
    uint64_t seed = 300;
    for (float roughness : {0.3f, 1.0f}) {
        for (float cz : {0.9f, 0.2f}) {
            Bsdf b = make_bsdf(Rgb(1.0f), 1.0f, roughness, 1.0f, Rgb(1.0f), 0.5f, 1.5f);  // metallic wins
            ASSERT_EQ(b.kind, BsdfKind::Principled);
            auto e = test::furnace(b, test::dir_from_cos(cz), 60000, ++seed);
            EXPECT_NEAR(e.mean, 1.0, 4.0 * e.se + 1e-5)
                << "r " << roughness << " cos " << cz;  // as the conductor
        }
    }
}

TEST(Principled, IsReciprocalWithoutTransmission) {
    Pcg32 rng(4, 4);
    for (float metallic : {0.0f, 0.4f}) {
        Bsdf b = principled(Rgb(0.7f, 0.5f, 0.2f), metallic, 0.5f, 0.0f, 0.8f);
        for (int i = 0; i < 200; ++i) {
            Vec3 wo = sample_cosine_hemisphere(rng.next_2d()), wi = sample_cosine_hemisphere(rng.next_2d());
            if (wo.z < 1e-3f || wi.z < 1e-3f) continue;
            Rgb a = bsdf_eval(b, wo, wi), c = bsdf_eval(b, wi, wo);
            for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], c[k], 1e-4f * std::fabs(a[k]) + 1e-7f);
        }
    }
}

TEST(Principled, PdfIntegratesToTheSamplingSuccessRate) {
    for (float transmission : {0.0f, 0.6f}) {
        Bsdf b = principled(Rgb(0.8f), 0.3f, 0.5f, transmission);
        for (float cz : {0.9f, 0.3f}) test::expect_pdf_normalised(b, test::dir_from_cos(cz), 200000, 17);
    }
}

TEST(Principled, ChiSquareOfSamplesAgainstPdf) {
    auto r = test::chi2_test(principled(Rgb(0.8f, 0.6f, 0.4f), 0.3f, 0.6f, 0.0f), test::dir_from_cos(0.5f),
                             200000, 19);
    EXPECT_LT(r.stat, r.threshold) << "dof " << r.dof;
    auto t = test::chi2_test(principled(Rgb(0.9f), 0.2f, 0.6f, 0.7f), test::dir_from_cos(0.7f), 200000, 23);
    EXPECT_LT(t.stat, t.threshold) << "dof " << t.dof;
}

TEST(Principled, SmoothGlassyMixIsPartlyDelta) {
    Bsdf b = principled(Rgb(1.0f), 0.0f, 0.0f, 0.5f);
    EXPECT_FALSE(bsdf_is_delta(b));  // the diffuse half still benefits from light sampling
    EXPECT_TRUE(bsdf_is_delta(principled(Rgb(1.0f), 0.5f, 0.0f, 1.0f)));
}

// Cycles' Principled v1 diffuse (Bsdf::burley_diffuse) against Burley's 2012 form, written here independently:
// base/pi (1 + (F_D90 - 1)(1 - mu_i)^5)(1 + (F_D90 - 1)(1 - mu_o)^5), F_D90 = 0.5 + 2 r cos^2(theta_d), theta_d
// the angle between wi and the half vector; the specular layer is the one without the flag (it is added beside).
TEST(Principled, BurleyDiffuseIsBurleys2012FormBesideTheSpecularLayer) {
    Pcg32 rng(8, 8);
    for (float roughness : {0.0f, 0.4f, 1.0f}) {
        Bsdf plain = principled(Rgb(0.0f), 0.0f, roughness, 0.0f);  // the specular layer alone
        Bsdf burley = principled(Rgb(0.6f, 0.3f, 0.9f), 0.0f, roughness, 0.0f);
        burley.burley_diffuse = true;
        for (int i = 0; i < 200; ++i) {
            Vec3 wo = sample_cosine_hemisphere(rng.next_2d()), wi = sample_cosine_hemisphere(rng.next_2d());
            if (wo.z < 1e-3f || wi.z < 1e-3f) continue;
            const double cos_d = dot(normalize(wo + wi), wi);
            const double fd90 = 0.5 + 2.0 * roughness * cos_d * cos_d;
            const double burley_factor = (1.0 + (fd90 - 1.0) * std::pow(1.0 - wi.z, 5.0)) *
                                         (1.0 + (fd90 - 1.0) * std::pow(1.0 - wo.z, 5.0)) / M_PI;
            const Rgb got = bsdf_eval(burley, wo, wi), spec = bsdf_eval(plain, wo, wi);
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(got[k] - spec[k], burley.base_color[k] * burley_factor, 1e-5) << "r " << roughness;
            const Rgb back = bsdf_eval(burley, wi, wo);  // reciprocal, as Burley's form is
            for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], back[k], 1e-4f * std::fabs(got[k]) + 1e-7f);
        }
    }
}

// Seen from the normal (mu_o = 1) Burley's white diffuse reflects 1 - 1/42 + 5 r / 84: the integral of its factor
// (1 - (1 - mu)^5 / 2) + r (1 + mu)(1 - mu)^5 against 2 mu d(mu). No specular layer (specular 0), so that the
// furnace sees the diffuse alone; sampled and evaluated through bsdf_sample.
TEST(Principled, BurleyDiffuseAlbedoAtNormalIncidenceIsAnalytic) {
    for (float roughness : {0.0f, 0.5f, 1.0f}) {
        Bsdf b = principled(Rgb(1.0f), 0.0f, roughness, 0.0f);
        b.specular = 0.0f;
        b.burley_diffuse = true;
        const auto e = test::furnace(b, Vec3(0.0f, 0.0f, 1.0f), 100000, 41);
        EXPECT_NEAR(e.mean, 1.0 - 1.0 / 42.0 + 5.0 * roughness / 84.0, 4.0 * e.se + 1e-4) << "r " << roughness;
    }
}

TEST(Principled, BurleyChiSquareOfSamplesAgainstPdf) {
    Bsdf b = principled(Rgb(0.8f, 0.6f, 0.4f), 0.0f, 0.6f, 0.0f);
    b.burley_diffuse = true;
    auto r = test::chi2_test(b, test::dir_from_cos(0.4f), 200000, 29);
    EXPECT_LT(r.stat, r.threshold) << "dof " << r.dof;
    test::expect_pdf_normalised(b, test::dir_from_cos(0.4f), 200000, 31);
}

}  // namespace
}  // namespace npt::materials
