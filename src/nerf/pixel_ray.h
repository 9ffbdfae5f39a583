// Camera rays straight into model space, for code that generates many of them (GPU training and rendering):
// a data-set camera with its camera-to-model matrix (world_to_model * camera_to_world) folded into floats. The
// same lens model as generate_pixel_ray; the direction agrees with transforming that world ray to model space
// up to float rounding.
#pragma once

#include "core/platform.h"
#include "core/vec.h"
#include "nerf/lens_distortion.h"

namespace npt {
struct Mat4;
}

namespace npt::nerf {

struct Camera;

struct RayCamera {
    float m[3][4] = {};  // camera-to-model, row-major; column 3 is the camera position in model space
    float fx = 1, fy = 1, cx = 0, cy = 0;
    LensDistortion lens;
    int width = 0, height = 0;
};

// Host side: folds world_to_model into the camera's pose.
RayCamera make_ray_camera(const Camera& camera, const Mat4& world_to_model);

// The model-space ray through image coordinates (px, py) of the (distorted) photo, unit direction; pixel
// centres are at +0.5, y runs down the image.
NPT_HD NPT_INLINE Ray pixel_ray(const RayCamera& c, float px, float py) {
    float x = (px - c.cx) / c.fx, y = (py - c.cy) / c.fy;
    if (!c.lens.is_identity()) undistort(c.lens, x, y, &x, &y);
    const Vec3 d_cam(x, -y, -1.0f);
    const Vec3 d(c.m[0][0] * d_cam.x + c.m[0][1] * d_cam.y + c.m[0][2] * d_cam.z,
                 c.m[1][0] * d_cam.x + c.m[1][1] * d_cam.y + c.m[1][2] * d_cam.z,
                 c.m[2][0] * d_cam.x + c.m[2][1] * d_cam.y + c.m[2][2] * d_cam.z);
    return Ray{Vec3(c.m[0][3], c.m[1][3], c.m[2][3]), normalize(d)};
}

}  // namespace npt::nerf
