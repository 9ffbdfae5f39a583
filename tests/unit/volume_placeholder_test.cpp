// The `volume` cube of cornell_volume is a placeholder for a NeRF: it is loaded and reported, never hit by
// rays.
#include <gtest/gtest.h>

#include "render/cpu/embree_scene.h"
#include "scene/scene.h"
#include "test_support.h"

namespace npt {
namespace {

TEST(VolumePlaceholder, CornellVolumeCubeIsLoadedButNotASurface) {
    auto path = test::shared_data() / "scenes" / "cornell_volume" / "scene.gltf";
    NPT_REQUIRE_SHARED(path);
    scene::Scene scene = scene::load_scene(path);
    ASSERT_EQ(scene.volumes.size(), 1u);
    EXPECT_EQ(scene.volumes[0].name, "volume");
    for (const auto& m : scene.meshes) EXPECT_NE(m.name, "volume");

    // A ray from the camera through the upper part of the cube (above the inner box) must pass through it and
    // hit the back wall; if the cube were a surface it would stop at the cube's front face (z = -0.25 + 0.5).
    render::cpu::EmbreeScene embree(scene);
    render::cpu::EmbreeTracer tracer(embree);
    Vec3 origin = scene.cameras.at(size_t(scene.camera)).position;
    Vec3 target = scene.volumes[0].local_to_world.transform_point(Vec3(0.0f, 0.9f, 0.0f));
    Ray ray{origin, normalize(target - origin)};
    render::Hit hit;
    ASSERT_TRUE(tracer.intersect(ray, INFINITY, &hit));
    EXPECT_EQ(scene.meshes[hit.mesh].name, "back");
    Vec3 p = ray.at(hit.t);
    EXPECT_LT(p.z, -0.9f);  // the back wall is at z = -1
}

}  // namespace
}  // namespace npt
