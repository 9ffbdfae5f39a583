// tiny-cuda-nn's hash-grid parameter layout (as instant-ngp snapshots store it) and its conversion to ours
// (hash_encoding.h). Both place a level's vertices at the same positions and hash them with the same
// function; they differ in the vertex count per axis (tiny-cuda-nn ceil(scale) + 1, ours + 2), in the dense
// index stride that follows from it, and in how a level's table is sized.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "nerf/hash_encoding.h"
#include "nerf/occupancy_grid.h"

namespace npt::nerf {

// One level of tiny-cuda-nn's GridEncoding (grid.h, common_device.h: grid_scale, grid_resolution,
// grid_index).
struct TcnnLevel {
    float scale = 0;          // position = p * scale + 0.5, as ours
    uint32_t resolution = 0;  // vertices per axis: ceil(scale) + 1
    uint32_t size = 0;        // table entries: min(next_multiple(resolution^3, 8), 2^log2_hashmap_size)
    bool dense = false;       // index = x + y*R + z*R^2 (mod size); else the coherent prime hash mod size
};

TcnnLevel tcnn_level(const HashGridConfig& cfg, float per_level_scale, int level);
// The table entry tiny-cuda-nn reads for vertex (x, y, z) of a level; coordinates may be `resolution`, which
// aliases into the next row (or wraps around the table) as tiny-cuda-nn does.
uint32_t tcnn_entry(const TcnnLevel& lv, uint32_t x, uint32_t y, uint32_t z);

// How one level was carried over. A level can be dense in the snapshot and hashed here (our extra vertex per
// axis pushes V^3 past the table size): then several of our vertices share an entry and the snapshot's values
// cannot all be kept; such a level is fitted by a weighted mean per entry, vertices next to occupied cells
// weighing most, and the report says how well that went.
struct NgpLevelReport {
    int level = 0;
    bool dense_in_snapshot = false;
    bool dense_here = false;
    bool exact = true;  // every vertex keeps the snapshot's value
    size_t vertices_checked =
        0;                    // inexact levels: vertices next to an occupied cell (all when none is known)
    size_t vertices_off = 0;  //   of those, how many differ from the snapshot's value
    float max_error = 0.0f;   //   and the largest difference (feature units)
};

// Converts tiny-cuda-nn's grid parameters `src` (levels one after another, tcnn_level(...).size entries of
// F features each) into ours `dst` (cfg.param_count() floats). cfg.per_level_scale must equal
// per_level_scale (then both give every level the same scale). `occupancy` weighs the fit of inexact levels.
std::vector<NgpLevelReport> convert_hash_grid(const HashGridConfig& cfg, float per_level_scale,
                                              const float* src, const OccupancyGrid& occupancy, float* dst);

}  // namespace npt::nerf
