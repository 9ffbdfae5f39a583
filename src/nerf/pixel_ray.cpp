#include "nerf/pixel_ray.h"

#include "core/transform.h"
#include "nerf/dataset.h"

namespace npt::nerf {

RayCamera make_ray_camera(const Camera& camera, const Mat4& world_to_model) {
    RayCamera rc;
    const Mat4 c2m = world_to_model * camera.camera_to_world;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) rc.m[r][c] = float(c2m.m[r][c]);
    rc.fx = camera.fx;
    rc.fy = camera.fy;
    rc.cx = camera.cx;
    rc.cy = camera.cy;
    rc.lens = camera.distortion();
    rc.width = camera.width;
    rc.height = camera.height;
    return rc;
}

}  // namespace npt::nerf
