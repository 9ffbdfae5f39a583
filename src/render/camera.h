// Primary rays: pixel (i, j), i rightwards and j downwards from the top-left, is the average radiance over
// its square footprint on the image plane (box filter of width one pixel).
#pragma once

#include "core/vec.h"
#include "render/scene_view.h"

namespace npt::render {

// `u` is uniform in [0,1)^2 over the pixel footprint.
NPT_HD NPT_INLINE Ray generate_camera_ray(const CameraView& cam, int i, int j, Vec2 u) {
    float x = (2.0f * (float(i) + u.x) / float(cam.width) - 1.0f) * cam.aspect * cam.tan_half_fov_y;
    float y = (1.0f - 2.0f * (float(j) + u.y) / float(cam.height)) * cam.tan_half_fov_y;
    Ray r;
    r.o = cam.position;
    r.d = normalize(cam.forward + cam.right * x + cam.up * y);
    return r;
}

}  // namespace npt::render
