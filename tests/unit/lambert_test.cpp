#include "materials/lambert.h"

#include <gtest/gtest.h>

#include "bsdf_test_util.h"

namespace npt::materials {
namespace {

using test::furnace;

Bsdf lambert(float albedo) { return make_bsdf(Rgb(albedo), 0.0f, 1.0f, 0.0f, Rgb(1.0f), 0.0f, 1.5f); }

TEST(Lambert, WhiteFurnaceReturnsAlbedo) {
    for (float albedo : {1.0f, 0.5f}) {
        Bsdf b = lambert(albedo);
        ASSERT_EQ(b.kind, BsdfKind::Lambert);
        for (float cz : {1.0f, 0.5f, 0.05f}) {
            auto e = furnace(b, test::dir_from_cos(cz), 20000, 3);
            // Cosine sampling makes every weight equal to the albedo (zero variance): only float rounding.
            EXPECT_NEAR(e.mean, albedo, 4.0 * e.se + 1e-6) << "albedo " << albedo << " cos " << cz;
        }
    }
}

TEST(Lambert, BelowHorizonIsBlackAndPdfIntegratesToOne) {
    Bsdf b = lambert(0.8f);
    Vec3 wo = test::dir_from_cos(0.7f);
    EXPECT_TRUE(is_black(bsdf_eval(b, wo, Vec3(0, 0, -1))));
    EXPECT_EQ(bsdf_pdf(b, wo, Vec3(0, 0.6f, -0.8f)), 0.0f);
    EXPECT_NEAR(bsdf_eval(b, wo, Vec3(0, 0, 1)).x, 0.8f * k_inv_pi, 1e-7f);
    auto e = test::pdf_integral(b, wo, 200000, 9);
    EXPECT_NEAR(e.mean, 1.0, 4.0 * e.se);  // 4 standard errors of the uniform-sphere MC mean, 2e5 samples
}

}  // namespace
}  // namespace npt::materials
