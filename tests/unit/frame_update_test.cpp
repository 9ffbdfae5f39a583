// A prepared CPU renderer updated to a frame (scene::pose_scene + CpuFrameRenderer::update: refitted Embree geometry,
// rebuilt light set, moved camera) renders the image a renderer built from scratch on the posed scene renders:
// the update misses nothing that moved. Same seed and sampler, so the images agree to float rounding (a refitted
// and a fresh BVH find the same hits; only exact ties could differ).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "render/cpu/cpu_renderer.h"
#include "scene/animation.h"
#include "scene/scene.h"
#include "test_support.h"

namespace npt::render {
namespace {

scene::Scene shot_scene() {
    // The animated example scene (scripts/make_shot_scene.py): tests/data is beside scenes/ in the source tree.
    return scene::load_scene(test::test_data().parent_path().parent_path() / "scenes" / "shot" / "scene.gltf");
}

TEST(FrameUpdate, UpdatedRendererMatchesAFreshOne) {
    scene::Scene moving = shot_scene();
    RenderOptions o;
    o.width = 24;
    o.height = 18;
    o.spp = 4;
    o.seed = 3;
    o.threads = 1;
    o.backend = "cpu";
    const RenderOptions resolved = resolve_options(moving, o);
    cpu::CpuFrameRenderer renderer(moving, resolved.width, resolved.height);
    for (double t : {0.5, 1.25, 2.0}) {
        const scene::PoseChanges changes = scene::pose_scene(moving, t);
        EXPECT_TRUE(changes.cameras);
        EXPECT_FALSE(changes.meshes.empty());
        renderer.update(changes);
        const Image updated = renderer.render(resolved, {});

        scene::Scene fresh = shot_scene();
        scene::pose_scene(fresh, t);
        const Image expected = cpu::CpuFrameRenderer(fresh, resolved.width, resolved.height).render(resolved, {});
        ASSERT_EQ(updated.pixels.size(), expected.pixels.size());
        double worst = 0;
        for (size_t i = 0; i < expected.pixels.size(); ++i)
            worst = std::max(worst, double(std::abs(updated.pixels[i] - expected.pixels[i])));
        EXPECT_LE(worst, 1e-5) << "at " << t << " s";
    }
    // And the pose matters: the rest pose renders differently from t = 2 s.
    scene::Scene rest = shot_scene();
    const Image at_rest = cpu::CpuFrameRenderer(rest, resolved.width, resolved.height).render(resolved, {});
    const Image at_end = renderer.render(resolved, {});
    double diff = 0;
    for (size_t i = 0; i < at_rest.pixels.size(); ++i) diff += std::abs(at_rest.pixels[i] - at_end.pixels[i]);
    EXPECT_GT(diff, 1.0);
}

}  // namespace
}  // namespace npt::render
