// Cameras that are not in any data set, for `nerfpt view`: a turntable orbit around the model, with world +Z
// up as in NeRF-synthetic and instant-ngp's world space, and the defaults that frame a model as its training
// cameras did.
#pragma once

#include "core/vec.h"
#include "nerf/dataset.h"
#include "nerf/nerf_model.h"

namespace npt::nerf {

// The model's cube [0,1]^3 has its centre at (0.5, 0.5, 0.5); this is that point in world space.
Vec3 model_centre_world(const NerfModel& model);

// World units per model unit inverted: the uniform scale of world_to_model (cube root of |det|).
double model_scale(const NerfModel& model);

// NeRF-synthetic's cameras sit 4.0 world units from the centre at instant-ngp's scale 0.33: 1.32 model units.
constexpr double k_default_orbit_model_distance = 4.0 * 0.33;
// The default orbit distance in world units: k_default_orbit_model_distance / model_scale (4.0 for a model
// trained on NeRF-synthetic).
double default_orbit_distance(const NerfModel& model);

struct OrbitSettings {
    Vec3 centre;                // world space
    double distance = 4.0;      // world units from the centre
    double elevation_deg = 30;  // above the XY plane; must be inside (-90, 90)
    int width = 800, height = 800;
    double fov_deg = 40;  // horizontal
};

// The camera at `azimuth_rad` (0: on the +X side of the centre, increasing counter-clockwise seen from +Z)
// looking at the centre, image up towards +Z; OpenGL convention like the data set cameras. Throws npt::Error
// for an elevation outside (-90, 90), a fov outside (0, 180), a non-positive distance or size.
Camera orbit_camera(const OrbitSettings& settings, double azimuth_rad);

// The pinhole focal length in pixels for a horizontal field of view over `width` pixels.
float focal_from_fov(int width, double fov_deg);

}  // namespace npt::nerf
