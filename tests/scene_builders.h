// Small scenes built in code for tests that go through the renderer without a file.
#pragma once

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

}  // namespace npt::test
