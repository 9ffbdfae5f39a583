// A tiny NeRF data set made in code: three shaded spheres seen from cameras on a sphere, rendered
// analytically (4x4 supersampled, transparent background), for training tests that must run in seconds.
#pragma once

#include <filesystem>

#include "nerf/dataset.h"

namespace npt::test {

struct SphereSceneOptions {
    int views = 20;
    int size = 32;            // square images
    uint32_t view_seed = 1;   // which camera positions (held-out views use another seed)
    float distance = 4.0f;    // camera distance from the origin; the spheres lie within radius 1
    float fov_degrees = 40.0f;
};

nerf::Dataset make_sphere_scene(const SphereSceneOptions& options);

// Writes the data set as PNG frames plus transforms.json (camera_angle_x, NeRF-synthetic style) into folder.
void write_dataset(const nerf::Dataset& ds, const std::filesystem::path& folder, float fov_degrees);

}  // namespace npt::test
