// The film's outputs beside the colour (--transparent's alpha, the albedo, normal and depth AOVs) on OptiX against
// the CPU backend at the same seed, in the per-thread form (a sphere under a sky) and in the wavefront form (a
// random NeRF in front of a quad: the first hit recorded between launches, with the NeRF pass's transmittance).
// The same sampler and integrator run on both, so a pixel differs only where a float-level difference moves a path
// (an intersection at a silhouette) or, in the wavefront form, by the fp16 network's rounding of the volume's
// transmittance. Registered only where a GPU exists (label gpu); skipped without the OptiX headers.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include "film_test_scenes.h"
#include "nerf/model_file.h"
#include "random_nerf_volume.h"
#include "render/backend/render_backend.h"
#include "test_support.h"

namespace npt {
namespace {

struct Film {
    Image image;
    render::AovImages aovs;
};

Film render_film(const scene::Scene& s, const std::string& backend, bool transparent, uint64_t seed) {
    render::RenderOptions o;
    o.width = 64;
    o.height = 48;
    o.spp = 16;
    o.seed = seed;
    o.backend = backend;
    o.transparent = transparent;
    o.aovs = render::k_aov_albedo | render::k_aov_normal | render::k_aov_depth;
    Film f;
    f.image = render::render_with_backend(s, render::resolve_options(s, o), {}, nullptr, &f.aovs);
    return f;
}

// Channel `c` of `a` and `b` (same layout) agree: at most `outlier_fraction` of the pixels differ by more than
// `tol` (relative above 1), and the means within `mean_tol` (relative above 1). Infinite depths must match.
void expect_channels_agree(const Image& a, const Image& b, const char* what, float tol, double outlier_fraction,
                           double mean_tol) {
    ASSERT_EQ(a.channels, b.channels) << what;
    ASSERT_EQ(a.pixels.size(), b.pixels.size()) << what;
    const size_t n = size_t(a.width) * size_t(a.height);
    for (int c = 0; c < a.channels; ++c) {
        size_t outliers = 0, finite = 0, inf_mismatch = 0;
        double sa = 0.0, sb = 0.0;
        for (size_t i = 0; i < n; ++i) {
            const float x = a.pixels[i * size_t(a.channels) + size_t(c)], y = b.pixels[i * size_t(b.channels) + size_t(c)];
            if (std::isinf(x) || std::isinf(y)) {
                inf_mismatch += x != y;
                continue;
            }
            ++finite;
            sa += x;
            sb += y;
            if (std::abs(x - y) > tol * std::max(1.0f, std::abs(y))) ++outliers;
        }
        std::printf("%s channel %d: %zu of %zu pixels beyond %g, %zu infinite mismatches, means %.5f / %.5f\n",
                    what, c, outliers, n, double(tol), inf_mismatch, sa / double(std::max<size_t>(finite, 1)),
                    sb / double(std::max<size_t>(finite, 1)));
        EXPECT_LE(double(outliers + inf_mismatch), outlier_fraction * double(n)) << what << " channel " << c;
        const double ma = sa / double(std::max<size_t>(finite, 1)), mb = sb / double(std::max<size_t>(finite, 1));
        EXPECT_NEAR(ma, mb, mean_tol * std::max(1.0, std::abs(mb))) << what << " channel " << c;
    }
}

// The alpha channel (the 4th) of two RGBA images as 1-channel images.
Image alpha_of(const Image& rgba) {
    Image a(rgba.width, rgba.height, 1);
    for (size_t i = 0; i < a.pixels.size(); ++i) a.pixels[i] = rgba.pixels[4 * i + 3];
    return a;
}

void expect_optix_film_matches_cpu(const scene::Scene& s, Rgb sky, const char* label, float tol,
                                   double outlier_fraction) {
    SCOPED_TRACE(label);
    const Film g = render_film(s, "optix", true, 5), c = render_film(s, "cpu", true, 5);
    ASSERT_EQ(g.image.channels, 4);
    expect_channels_agree(alpha_of(g.image), alpha_of(c.image), "alpha", tol, outlier_fraction, 1e-3);
    expect_channels_agree(g.aovs.albedo, c.aovs.albedo, "albedo", tol, outlier_fraction, 1e-3);
    expect_channels_agree(g.aovs.normal, c.aovs.normal, "normal", tol, outlier_fraction, 1e-3);
    expect_channels_agree(g.aovs.depth, c.aovs.depth, "depth", tol, outlier_fraction, 1e-3);
    // On OptiX alone: the opaque render is the transparent one composited over the sky (the same paths).
    const Film opaque = render_film(s, "optix", false, 5);
    ASSERT_EQ(opaque.image.channels, 3);
    for (int y = 0; y < g.image.height; ++y)
        for (int x = 0; x < g.image.width; ++x)
            for (int k = 0; k < 3; ++k) {
                const float o = opaque.image.at(x, y)[k];
                ASSERT_NEAR(g.image.at(x, y)[k] + (1.0f - g.image.at(x, y)[3]) * sky[k], o, 1e-5f * (1.0f + o))
                    << x << "," << y << " channel " << k;
            }
}

TEST(OptixFilm, SphereAlphaAndAovsMatchTheCpu) {
    if (!render::optix_backend_built()) GTEST_SKIP() << "built without the OptiX backend";
    const Rgb sky(0.5f, 0.6f, 0.7f);
    // Silhouette pixels may differ where an intersection rounds the other way: at most 2% of them.
    expect_optix_film_matches_cpu(test::sphere_under_sky(Rgb(0.8f, 0.3f, 0.2f), sky), sky, "sphere", 1e-4f, 0.02);
}

TEST(OptixFilm, NerfInFrontOfAQuadMatchesTheCpuInBothForms) {
    if (!render::optix_backend_built()) GTEST_SKIP() << "built without the OptiX backend";
    const auto dir = test::temp_dir();
    nerf::NerfConfig c;  // the default network: the shape the NeRF pass's fp16 kernels take
    c.encoding.grid.log2_table_size = 14;
    c.encoding.finest_resolution = 128;
    c.occupancy.resolution = 32;
    std::mt19937 g(11);
    test::RandomNerfVolume nerf_volume(c, g, 1.0f, 0.5f);
    nerf::save_model(dir / "random.npt", nerf_volume.model, false);
    const Rgb sky(0.4f, 0.5f, 0.6f);
    scene::Scene s = test::quad_facing_camera(Rgb(0.3f, 0.6f, 0.2f), 0.5f, sky);
    s.meshes[0].positions = {Vec3(-1.5f, -1.0f, -1.0f), Vec3(0.5f, -1.0f, -1.0f), Vec3(0.5f, 1.0f, -1.0f),
                             Vec3(-1.5f, 1.0f, -1.0f)};
    s.source = dir / "scene.gltf";
    scene::VolumeInstance v;
    v.name = "nerf";
    v.local_to_world = Mat4::scale(0.6f, 0.6f, 0.6f);
    v.extras_json = R"({"volume": {"file": "random.npt", "density_scale": 0.3, "emission_scale": 1.5}})";
    v.declared_in = dir / "scene.gltf";
    s.volumes = {v};
    // The fp16 network moves the transmittance by a few 1e-3: a looser tolerance than the sphere's.
    expect_optix_film_matches_cpu(s, sky, "wavefront", 1e-2f, 0.05);
    setenv("NERFPT_OPTIX_WAVEFRONT", "0", 1);
    expect_optix_film_matches_cpu(s, sky, "per thread", 1e-3f, 0.02);
    unsetenv("NERFPT_OPTIX_WAVEFRONT");
}

}  // namespace
}  // namespace npt
