// The .npt model file (docs/formats.md): magic and version, the JSON config, aabb_scale and world_to_model,
// the parameters, the occupancy grid, optionally the training state, and a checksum over everything. Written
// atomically (temporary file in the same folder, fsync, rename), so a crash never leaves a half-written model.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>

#include "nerf/nerf_model.h"

namespace npt::nerf {

// Writes `model` (with its training state when it has one and with_training is true). Throws npt::Error
// naming the path when the folder is not writable or the disk is full; the old file stays as it was.
void save_model(const std::filesystem::path& path, const NerfModel& model, bool with_training = true);

// Reads a model file. Throws npt::Error naming the path and what is wrong: not a model file, unsupported
// version, truncated, checksum mismatch, sizes that do not match the stored config, non-finite values.
NerfModel load_model(const std::filesystem::path& path);

// The file's checksum (docs/formats.md) over `size` bytes; exposed so that tests and tools can craft files.
uint64_t model_file_hash(const void* data, size_t size);

}  // namespace npt::nerf
