#include "materials/conductor.h"

#include <gtest/gtest.h>

#include "bsdf_test_util.h"

namespace npt::materials {
namespace {

Bsdf conductor(float roughness, Rgb f0 = Rgb(1.0f)) {
    return make_bsdf(f0, 1.0f, roughness, 1.0f, Rgb(1.0f), 0.0f, 1.5f);
}

// With F0 = 1 the multiple-scattering compensation must return every bit of energy single scattering loses.
TEST(Conductor, WhiteFurnaceConservesEnergyAtEveryRoughness) {
    uint64_t seed = 1;
    for (float roughness : {0.0f, 0.1f, 0.3f, 0.5f, 0.8f, 1.0f}) {
        Bsdf b = conductor(roughness);
        ASSERT_EQ(b.kind, BsdfKind::Conductor);
        EXPECT_EQ(bsdf_is_delta(b), roughness == 0.0f);
        for (float cz : {1.0f, 0.7f, 0.3f, 0.05f}) {
            auto e = test::furnace(b, test::dir_from_cos(cz), 100000, ++seed);
            // 4 standard errors of the MC mean over 1e5 samples, plus 1e-5 for float rounding of the weights
            // (the delta case has zero variance).
            EXPECT_NEAR(e.mean, 1.0, 4.0 * e.se + 1e-5) << "roughness " << roughness << " cos " << cz;
        }
    }
}

TEST(Conductor, SingleScatteringAloneWouldLoseEnergy) {
    // Guards the test above against a compensation that does nothing: at r = 1 the single-scattering albedo
    // (the table) is well below 1, so the furnace result depends on the extra lobe.
    EXPECT_LT(ggx_albedo(1.0f, 0.5f), 0.9f);
    EXPECT_LT(ggx_albedo(0.09f, 0.05f), 0.97f);  // r = 0.3 at the grazing angle the test uses
}

TEST(Conductor, IsReciprocal) {
    Pcg32 rng(3, 3);
    for (float roughness : {0.1f, 0.4f, 1.0f}) {
        Bsdf b = conductor(roughness, Rgb(0.9f, 0.6f, 0.3f));
        for (int i = 0; i < 200; ++i) {
            Vec3 wo = sample_cosine_hemisphere(rng.next_2d()), wi = sample_cosine_hemisphere(rng.next_2d());
            if (wo.z < 1e-3f || wi.z < 1e-3f) continue;
            Rgb a = bsdf_eval(b, wo, wi), c = bsdf_eval(b, wi, wo);
            for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], c[k], 1e-4f * std::fabs(a[k]) + 1e-7f);
        }
    }
}

TEST(Conductor, PdfIntegratesToTheSamplingSuccessRate) {
    for (float roughness : {0.3f, 0.6f, 1.0f}) {
        for (float cz : {0.9f, 0.4f}) {
            // Not exactly 1: visible normals whose mirror direction points below the horizon yield no sample.
            test::expect_pdf_normalised(conductor(roughness), test::dir_from_cos(cz), 200000, 11);
        }
    }
}

TEST(Conductor, ChiSquareOfSamplesAgainstPdf) {
    for (float roughness : {0.5f, 0.9f}) {
        auto r =
            test::chi2_test(conductor(roughness, Rgb(0.8f, 0.5f, 0.2f)), test::dir_from_cos(0.6f), 200000, 5);
        EXPECT_LT(r.stat, r.threshold) << "roughness " << roughness << " dof " << r.dof;
        EXPECT_GT(r.dof, 50);
    }
}

}  // namespace
}  // namespace npt::materials
