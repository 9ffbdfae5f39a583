// A tiny NeRF data set made in code: three shaded spheres seen from cameras on a sphere, rendered
// analytically (4x4 supersampled, transparent background), for training tests that must run in seconds.
#pragma once

#include <filesystem>

#include "nerf/dataset.h"
#include "nerf/nerf_config.h"

namespace npt::test {

struct SphereSceneOptions {
    int views = 20;
    int size = 32;            // square images
    uint32_t view_seed = 1;   // which camera positions (held-out views use another seed)
    float distance = 4.0f;    // camera distance from the origin; the spheres lie within radius 1
    float fov_degrees = 40.0f;
};

nerf::Dataset make_sphere_scene(const SphereSceneOptions& options);

// instant-ngp's config scaled down for the sphere scene's 32 px images: 8 levels up to 128 cells, 2^15 entries,
// a 32^3 occupancy grid, 2^13-sample steps; the grid schedule counts instant-ngp steps of 2^18 samples, i.e.
// an update every 32 of these steps, the first 8 over every cell.
nerf::NerfConfig small_sphere_config();

// Writes the data set as PNG frames plus transforms.json (camera_angle_x, NeRF-synthetic style) into folder.
void write_dataset(const nerf::Dataset& ds, const std::filesystem::path& folder, float fov_degrees);

}  // namespace npt::test
