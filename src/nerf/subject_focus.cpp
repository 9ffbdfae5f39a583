#include "nerf/subject_focus.h"

#include <algorithm>

#include "core/transform.h"

namespace npt::nerf {

std::vector<PixelRect> subject_rects(const std::vector<Camera>& cameras, const std::array<Vec3, 8>& corners,
                                     float margin_px) {
    std::vector<PixelRect> rects;
    rects.reserve(cameras.size());
    for (const Camera& cam : cameras) {
        const PixelRect whole{0.0f, 0.0f, float(cam.width), float(cam.height)};
        const Mat4 world_to_camera = cam.camera_to_world.inverse();
        PixelRect r{1e30f, 1e30f, -1e30f, -1e30f};
        bool behind = false;
        for (const Vec3& corner : corners) {
            // The camera looks down -z with y up (generate_pixel_ray): depth is -z, and y runs down the
            // image.
            const Vec3 p = world_to_camera.transform_point(corner);
            const float depth = -p.z;
            if (!(depth > 1e-4f)) {
                behind = true;
                break;
            }
            // Without the lens's distortion: the margin covers what it moves.
            const float px = cam.cx + cam.fx * p.x / depth, py = cam.cy - cam.fy * p.y / depth;
            r.x0 = std::min(r.x0, px), r.x1 = std::max(r.x1, px);
            r.y0 = std::min(r.y0, py), r.y1 = std::max(r.y1, py);
        }
        if (behind) {
            rects.push_back(whole);
            continue;
        }
        r.x0 = std::clamp(r.x0 - margin_px, 0.0f, whole.x1);
        r.x1 = std::clamp(r.x1 + margin_px, 0.0f, whole.x1);
        r.y0 = std::clamp(r.y0 - margin_px, 0.0f, whole.y1);
        r.y1 = std::clamp(r.y1 + margin_px, 0.0f, whole.y1);
        // Off the image, or less than a pixel of it: nothing to focus on.
        rects.push_back(r.x1 - r.x0 >= 1.0f && r.y1 - r.y0 >= 1.0f ? r : whole);
    }
    return rects;
}

}  // namespace npt::nerf
