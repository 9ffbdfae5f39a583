// The GPU marches' form of an occupancy grid, made on the host from its byte flags: one bit per cell, one bit
// per coarse cell where the resolution allows (OccupancyGridView), and the box around the occupied cells (the
// marches start and end there: march_clip). Used by the view renderer and the path tracer's NeRF pass.
#pragma once

#include <cstdint>
#include <vector>

#include "core/vec.h"
#include "nerf/occupancy_view.h"

namespace npt::nerf::cuda {

struct OccupancyBits {
    std::vector<uint32_t> occupied;  // OccupancyGridView::occupied_bits
    std::vector<uint32_t> coarse;    // OccupancyGridView::coarse_bits; empty when the resolution does not allow
    Vec3 box_min{1e30f}, box_max{-1e30f};  // empty (min > max) when no cell is occupied
};

// `grid` must have its byte flags (`occupied`) on the host.
OccupancyBits occupancy_bits(const OccupancyGridView& grid);

}  // namespace npt::nerf::cuda
