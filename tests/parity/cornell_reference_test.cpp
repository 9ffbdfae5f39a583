// Our render of the shared Cornell scene against Blender Cycles' 4512 spp reference
// (../shared/data/scenes/cornell).
//
// Tolerance derivation. We render two independent halves a, b (different seeds) and compare their mean m with
// the reference r. Per pixel and channel, E[(m - r)^2] = Var(m) + Var(r) + bias^2, and (a - b)^2 / 4 is an
// unbiased estimate of Var(m). So d = (m - r)^2 w - (a - b)^2 w / 4, with w = 1 / (r^2 + 0.01), has
// expectation Var(r) w + bias^2 w: averaged over the image that is the reference's own relMSE (measured by
// the data's authors from its two halves and stated in reference.json) plus our bias. We require mean(d) <=
// ref_rel_mse + 4 SE(d), with SE(d) the standard error of mean(d) over the pixels: a renderer with a bias
// much larger than the noise fails. The per-channel image means must agree within 4 combined standard errors
// (ours from a, b; the reference's from its stated per-channel MSE, treating pixels as independent).
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "core/image_io.h"
#include "core/image_stats.h"
#include "render/renderer.h"
#include "scene/scene.h"
#include "test_support.h"

namespace npt {
namespace {

struct ReferenceCase {
    std::filesystem::path folder;
    int spp_per_half;
};

void check_against_reference(const ReferenceCase& c) {
    auto scene_path = c.folder / "scene.gltf";
    NPT_REQUIRE_SHARED(scene_path);
    scene::Scene scene = scene::load_scene(scene_path);
    Image ref = read_image(c.folder / "reference.exr");
    nlohmann::json info = nlohmann::json::parse(std::ifstream(c.folder / "reference.json"));
    double ref_rel_mse = info["noise"]["rel_mse"].get<double>();

    render::RenderOptions o;
    o.width = ref.width;
    o.height = ref.height;
    o.spp = c.spp_per_half;
    o.seed = 1;
    Image a = render::render(scene, render::resolve_options(scene, o));
    o.seed = 2;
    Image b = render::render(scene, render::resolve_options(scene, o));
    Image m = average(a, b);

    ImageComparison cmp = compare_images(m, ref);
    NoiseEstimate noise = estimate_noise(a, b, ref);
    std::printf("relMSE %.3g (noise explains %.3g, reference %.3g; excess %.3g +- %.3g)\n", cmp.rel_mse,
                noise.rel_mse_expected, ref_rel_mse, noise.rel_mse_excess, noise.rel_mse_excess_stderr);
    EXPECT_LE(noise.rel_mse_excess, ref_rel_mse + 4.0 * noise.rel_mse_excess_stderr);

    auto mse = info["noise"]["mse_per_channel"];
    size_t n = size_t(ref.width) * size_t(ref.height);
    for (size_t k = 0; k < 3; ++k) {
        double ref_se = std::sqrt(mse[k].get<double>() * double(n)) / double(n);
        double se = std::sqrt(noise.mean_stderr[k] * noise.mean_stderr[k] + ref_se * ref_se);
        std::printf("channel %zu: mean %.5f vs %.5f (rel %.2e, 4 SE %.2e)\n", k, cmp.mean_test[k],
                    cmp.mean_ref[k], cmp.mean_rel_err[k], 4 * se / cmp.mean_ref[k]);
        EXPECT_LE(std::abs(cmp.mean_test[k] - cmp.mean_ref[k]), 4.0 * se) << "channel " << k;
    }
}

TEST(CornellReference, MatchesCyclesWithinNoise) {
    check_against_reference({test::shared_data() / "scenes" / "cornell", 64});
}

// The same room with an emission-absorption volume (OpenVDB grid), partly behind the sphere, with a box inside it.
// Same tolerance derivation; the reference's own noise is larger here (256 spp), and stated in its reference.json.
TEST(CornellVolumeReference, MatchesCyclesWithinNoise) {
    check_against_reference({test::shared_data() / "scenes" / "cornell_volume", 32});
}

}  // namespace
}  // namespace npt
