// Imports instant-ngp NeRF snapshots (.msgpack, or the zlib/gzip-compressed .ingp) as a NerfModel: the
// network config the testbed trained with becomes a NerfConfig, tiny-cuda-nn's padded fp16 (or fp32)
// parameter array becomes ours, and the Morton-ordered density grid becomes the occupancy grid. The supported
// layout and what is refused are in docs/formats.md, "instant-ngp snapshots".
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "nerf/nerf_model.h"
#include "nerf/ngp_hash_grid.h"

namespace npt::nerf {

struct NgpImport {
    NerfModel model;
    std::vector<NgpLevelReport> levels;
    std::vector<std::string> notes;  // assumptions worth telling the user (one line each)
    uint64_t training_step = 0;
};

// Reads and converts a snapshot file. Throws npt::Error naming the file and the field for anything missing,
// malformed or unsupported (encoding other than HashGrid, activations other than ReLU, widths over 128, ...).
NgpImport import_ngp_snapshot(const std::filesystem::path& path);
// The same for a file already in memory; `source` names it in messages.
NgpImport import_ngp_snapshot(const std::vector<uint8_t>& file_bytes, const std::string& source);

// Exposed for tests and tools.
float ngp_half_to_float(uint16_t h);
uint32_t ngp_morton3(uint32_t x, uint32_t y,
                     uint32_t z);  // tiny-cuda-nn's morton3D: x in bit 0, y bit 1, z bit 2
// instant-ngp's density grid (cascade after cascade, cells in Morton order, optical thickness of a minimum
// step; negative = never trained) as our occupancy densities (x fastest, negatives as 0).
std::vector<float> ngp_density_grid_to_occupancy(const std::vector<float>& ngp, int cascades, int resolution,
                                                 const std::string& source);

}  // namespace npt::nerf
