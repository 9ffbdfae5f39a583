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

}  // namespace
}  // namespace npt::materials
