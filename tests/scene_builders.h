// Small scenes built in code for tests that go through the renderer without a file.
#pragma once

#include "core/rng.h"
#include "render/cpu/embree_scene.h"
#include "render/path_integrator.h"
#include "render/scene_data.h"
#include "scene/scene.h"

namespace npt::test {

// A parallelogram corner, corner + u, corner + u + v, corner + v; its front face looks along cross(u, v).
inline scene::Mesh make_quad(Vec3 corner, Vec3 u, Vec3 v, int material) {
    scene::Mesh m;
    m.name = "quad";
    m.material = material;
    m.positions = {corner, corner + u, corner + u + v, corner + v};
    m.indices = {0, 1, 2, 0, 2, 3};
    return m;
}

// One path of `ray` through `s` on the CPU backend, with a fixed seed: for tests whose scenes have a closed
// form (the radiance does not depend on the random numbers, or the test averages itself).
inline Rgb trace_one_path(const scene::Scene& s, Ray ray, int max_depth = 4) {
    render::SceneData data(s, 8, 8);
    render::cpu::EmbreeScene embree(s);
    render::cpu::EmbreeTracer tracer(embree);
    render::PathSettings ps;
    ps.max_depth = max_depth;
    Pcg32 rng(1, 2);
    return render::trace_path(data.view(), tracer, ray, rng, ps);
}

}  // namespace npt::test
