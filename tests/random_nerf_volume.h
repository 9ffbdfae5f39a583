// A NeRF model with random hash features and a random occupancy grid in a rotated, scaled `volume` cube, and rays
// aimed into it: the volume that the NeRF integration tests march (the CPU's batched and per-point evaluation,
// the GPU's per-thread evaluation and its NeRF pass). Header-only, for tests.
#pragma once

#include <random>
#include <vector>

#include "core/transform.h"
#include "media/placement.h"
#include "media/volume.h"
#include "nerf/nerf_model.h"

namespace npt::test {

struct RandomNerfVolume {
    nerf::NerfModel model;
    media::VolumeView view;  // points into model: not copyable

    // Hash features uniform in [-feature_amplitude, feature_amplitude] (large enough that density and colour vary
    // along every ray), each occupancy cell occupied with probability occupied_fraction (empty cells to skip).
    // Draws from g: the features, then the cells.
    RandomNerfVolume(const nerf::NerfConfig& c, std::mt19937& g, float feature_amplitude, float occupied_fraction)
        : model(nerf::create_model(c, 1.0f, nerf::ngp_world_to_model(0.33f, Vec3(0.5f)))) {
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        const nerf::NerfLayout layout = model.layout();
        for (size_t i = layout.grid_offset; i < layout.total; ++i)
            model.params[i] = feature_amplitude * (2.0f * u(g) - 1.0f);
        std::vector<float> occ(model.occupancy.cell_count());
        for (float& o : occ) o = u(g) < occupied_fraction ? 1.0f : 0.0f;
        model.occupancy.set_density(occ, 0.5f);
        view.kind = media::VolumeKind::Nerf;
        view.nerf.field = model.field();
        view.nerf.occupancy = model.occupancy.view();
        view.nerf.march = model.march_params();
        view.nerf.local_to_model = nerf::local_to_model(Vec3(-1.0f), Vec3(1.0f), nerf::CropBox{});
        view.world_to_local = media::affine_from(
            (Mat4::translation(0.1, 0.2, -0.3) * Mat4::rotation_quat(0.2, 0.1, 0.3, 0.9) * Mat4::scale(0.7, 0.5, 0.6))
                .inverse());
    }
    RandomNerfVolume(const RandomNerfVolume&) = delete;
    RandomNerfVolume& operator=(const RandomNerfVolume&) = delete;
};

// A ray from the plane z = 3 towards a random point near the cube's centre; *target_t is the distance to that
// point (a surface inside the cube, for tests that end segments there).
inline Ray ray_into_random_nerf_volume(std::mt19937& g, float* target_t) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const Vec3 origin{u(g) * 4 - 2, u(g) * 4 - 2, 3.0f};
    const Vec3 target{0.1f + (u(g) - 0.5f), 0.2f + (u(g) - 0.5f), -0.3f + (u(g) - 0.5f)};
    *target_t = length(target - origin);
    return Ray{origin, normalize(target - origin)};
}

}  // namespace npt::test
