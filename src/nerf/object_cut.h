// The object's box as a test of model-space points (issue 25): what a `volume` cube with "placement": "object"
// cuts away, for the view renderers on the CPU and on the GPU (render_view.cpp, cuda/render_kernels.cu), which
// must drop the same samples. Plain floats, so that one test runs on both.
#pragma once

#include "core/platform.h"
#include "core/vec.h"

namespace npt::nerf {

struct ObjectCut {
    bool active = false;  // false: nothing is cut
    // Model space -> object space (+Z up, the supporting plane at z = 0): the rows of a 3x4 affine map.
    float m[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    Vec3 box_min{0.0f, 0.0f, 0.0f}, box_max{0.0f, 0.0f, 0.0f};  // the object's box, object space

    NPT_HD bool outside(Vec3 p) const {
        if (!active) return false;
        const float x = m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3];
        const float y = m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7];
        const float z = m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11];
        return x < box_min.x || y < box_min.y || z < box_min.z || x > box_max.x || y > box_max.y ||
               z > box_max.z;
    }
};

}  // namespace npt::nerf
