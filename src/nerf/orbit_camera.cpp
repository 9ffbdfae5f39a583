#include "nerf/orbit_camera.h"

#include <cmath>
#include <numbers>
#include <string>

#include "core/error.h"

namespace npt::nerf {

Vec3 model_centre_world(const NerfModel& model) {
    return model.world_to_model.inverse().transform_point(Vec3(0.5f, 0.5f, 0.5f));
}

double model_scale(const NerfModel& model) {
    return std::cbrt(std::abs(model.world_to_model.determinant3()));
}

double default_orbit_distance(const NerfModel& model) {
    const double s = model_scale(model);
    if (!(s > 0) || !std::isfinite(s)) throw Error("model: world_to_model has no usable scale");
    return k_default_orbit_model_distance / s;
}

float focal_from_fov(int width, double fov_deg) {
    return float(0.5 * double(width) / std::tan(0.5 * fov_deg * std::numbers::pi / 180.0));
}

Camera orbit_camera(const OrbitSettings& s, double azimuth_rad) {
    if (!(s.elevation_deg > -90 && s.elevation_deg < 90))
        throw Error("orbit: elevation " + std::to_string(s.elevation_deg) +
                    " must be inside (-90, 90) degrees");
    if (!(s.fov_deg > 0 && s.fov_deg < 180))
        throw Error("orbit: field of view " + std::to_string(s.fov_deg) + " must be inside (0, 180) degrees");
    if (!(s.distance > 0) || !std::isfinite(s.distance))
        throw Error("orbit: distance " + std::to_string(s.distance) + " must be positive");
    if (s.width <= 0 || s.height <= 0) throw Error("orbit: the image has no pixels");
    const double el = s.elevation_deg * std::numbers::pi / 180.0;
    const double dir[3] = {std::cos(el) * std::cos(azimuth_rad), std::cos(el) * std::sin(azimuth_rad),
                           std::sin(el)};
    const double c[3] = {s.centre.x, s.centre.y, s.centre.z};
    const double pos[3] = {c[0] + s.distance * dir[0], c[1] + s.distance * dir[1],
                           c[2] + s.distance * dir[2]};
    // The camera's +Z points away from what it looks at (OpenGL): back = dir. right = forward x world up
    // = (-dir_y, dir_x, 0) / |.|, never zero inside (-90, 90); camera up = back x right.
    const double h = std::hypot(dir[0], dir[1]);
    const double right[3] = {-dir[1] / h, dir[0] / h, 0.0};
    const double up[3] = {dir[1] * right[2] - dir[2] * right[1], dir[2] * right[0] - dir[0] * right[2],
                          dir[0] * right[1] - dir[1] * right[0]};
    Camera cam;
    for (int r = 0; r < 3; ++r) {
        cam.camera_to_world.m[size_t(r)][0] = right[r];
        cam.camera_to_world.m[size_t(r)][1] = up[r];
        cam.camera_to_world.m[size_t(r)][2] = dir[r];
        cam.camera_to_world.m[size_t(r)][3] = pos[r];
    }
    cam.width = s.width;
    cam.height = s.height;
    cam.fx = cam.fy = focal_from_fov(s.width, s.fov_deg);
    cam.cx = 0.5f * float(s.width);
    cam.cy = 0.5f * float(s.height);
    return cam;
}

}  // namespace npt::nerf
