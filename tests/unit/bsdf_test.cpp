#include "materials/bsdf.h"

#include <gtest/gtest.h>

#include "bsdf_test_util.h"

namespace npt::materials {
namespace {

TEST(Bsdf, MakeBsdfPicksKindFromGltfParameters) {
    Rgb w(1.0f);
    EXPECT_EQ(make_bsdf(w, 0, 0.5f, 0, w, 0, 1.5f).kind, BsdfKind::Lambert);
    EXPECT_EQ(make_bsdf(w, 1, 0.5f, 1, w, 0, 1.5f).kind, BsdfKind::Conductor);
    EXPECT_EQ(make_bsdf(w, 0, 0.5f, 1, w, 1, 1.5f).kind, BsdfKind::Dielectric);
    EXPECT_EQ(make_bsdf(w, 0, 0.5f, 1, w, 0, 1.5f).kind, BsdfKind::Principled);
    EXPECT_EQ(make_bsdf(w, 0.5f, 0.5f, 1, w, 0, 1.5f).kind, BsdfKind::Principled);
    EXPECT_EQ(make_bsdf(w, 0, 0.5f, 0, w, 1, 1.5f).kind, BsdfKind::Principled);
    EXPECT_FALSE(bsdf_has_transmission(make_bsdf(w, 1, 0.5f, 1, w, 0, 1.5f)));
    EXPECT_TRUE(bsdf_has_transmission(make_bsdf(w, 0.2f, 0.5f, 1, w, 0.3f, 1.5f)));
}

void expect_rel(Rgb a, Rgb b, const char* what, int i) {
    for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(a[k], b[k], 1e-4f * std::fabs(b[k]) + 1e-8f)
            << what << " channel " << k << " sample " << i;
}

// For non-delta samples the integrator's MIS needs f and pdf to be exactly what eval/pdf return.
TEST(Bsdf, SampleAgreesWithEvalAndPdf) {
    Rgb c(0.8f, 0.5f, 0.3f), sc(1.0f, 0.9f, 0.8f);
    Bsdf configs[] = {
        make_bsdf(c, 0, 1, 0, sc, 0, 1.5f),          make_bsdf(c, 1, 0.2f, 1, sc, 0, 1.5f),
        make_bsdf(c, 1, 0.7f, 1, sc, 0, 1.5f),       make_bsdf(c, 0, 0.2f, 1, sc, 1, 1.5f),
        make_bsdf(c, 0, 0.8f, 0.7f, sc, 1, 1.33f),   make_bsdf(c, 0, 0.5f, 1, sc, 0, 1.5f),
        make_bsdf(c, 0.5f, 0.3f, 0.5f, sc, 0, 1.5f), make_bsdf(c, 0.2f, 0.6f, 1, sc, 0.6f, 1.5f),
        make_bsdf(c, 0, 0.0f, 1, sc, 0.5f, 1.5f),    make_bsdf(c, 0, 0.9f, 1, sc, 1.0f, 1.5f),
    };
    Pcg32 rng(12, 12);
    for (const Bsdf& b : configs) {
        int non_delta = 0;
        for (int i = 0; i < 2000; ++i) {
            Vec3 wo = sample_uniform_sphere(rng.next_2d());
            if (!bsdf_has_transmission(b)) wo.z = std::fabs(wo.z);
            if (std::fabs(wo.z) < 1e-3f) continue;
            BsdfSample s;
            float u_lobe = rng.next_float();
            if (!bsdf_sample(b, wo, u_lobe, rng.next_2d(), &s)) continue;
            ASSERT_TRUE(is_finite(s.f) && std::isfinite(s.pdf) && s.pdf > 0.0f);
            ASSERT_NEAR(length(s.wi), 1.0f, 1e-4f);
            if (s.is_delta) continue;
            ++non_delta;
            expect_rel(s.f, bsdf_eval(b, wo, s.wi), "f", i);
            EXPECT_NEAR(s.pdf, bsdf_pdf(b, wo, s.wi), 1e-4f * s.pdf) << "sample " << i;
        }
        EXPECT_GT(non_delta, 300) << "kind " << int(b.kind) << " roughness " << b.roughness;
    }
}

TEST(Bsdf, DeltaLobesHaveNoEvalOrPdf) {
    Bsdf mirror = make_bsdf(Rgb(1.0f), 1, 0, 1, Rgb(1.0f), 0, 1.5f);
    EXPECT_TRUE(bsdf_is_delta(mirror));
    Vec3 wo = test::dir_from_cos(0.6f);
    BsdfSample s;
    ASSERT_TRUE(bsdf_sample(mirror, wo, 0.5f, Vec2(0.5f, 0.5f), &s));
    EXPECT_TRUE(s.is_delta);
    EXPECT_TRUE(is_black(bsdf_eval(mirror, wo, s.wi)));
    EXPECT_EQ(bsdf_pdf(mirror, wo, s.wi), 0.0f);
}

}  // namespace
}  // namespace npt::materials
