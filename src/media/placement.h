// Host transforms (double Mat4) to the float affine maps the per-sample volume code reads.
#pragma once

#include "core/transform.h"
#include "media/grid.h"

namespace npt::media {

inline Affine3 affine_from(const Mat4& m) {
    Affine3 a;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) a.m[r * 3 + c] = float(m.m[size_t(r)][size_t(c)]);
    a.t = Vec3(float(m.m[0][3]), float(m.m[1][3]), float(m.m[2][3]));
    return a;
}

}  // namespace npt::media
