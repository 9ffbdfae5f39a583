// Writers for a baked grid (bake_grid.h): OpenVDB 10 (.vdb), NanoVDB (.nvdb) and instant-ngp's raw RGBA-σ
// grid ({W}x{H}x{D}_*.bin), each read back by media/load_volume_grid. Every writer writes a temporary file in
// the destination folder and renames it into place, so an error or a crash never leaves a half-written grid.
#pragma once

#include <filesystem>
#include <string>

#include "bake/bake_grid.h"

namespace npt::bake {

enum class GridFormat { vdb, nvdb, raw };

// "vdb", "nvdb" or "raw"; throws npt::Error naming --format otherwise.
GridFormat grid_format_from_name(const std::string& name);
// By the output's extension: .vdb, .nvdb, .bin (case-insensitive); throws npt::Error naming --output.
GridFormat grid_format_from_path(const std::filesystem::path& path);
// Throws npt::Error naming --output when the extension does not say `format` (the readers pick by it).
void check_extension(const std::filesystem::path& path, GridFormat format);

// The raw file's name must carry its size ({W}x{H}x{D}, media/raw_grid_reader.h): `out` itself when its name
// already says the layout's size, else `out` with "WxHxD_" put in front of the file name. Throws npt::Error
// when the name says another size.
std::filesystem::path raw_output_path(const std::filesystem::path& out, const BakeLayout& layout);
// A raw grid is dense: refuses (npt::Error naming --res) more voxels than the renderer's dense loader takes.
void check_raw_size(const BakeLayout& layout);

// Grids "density" (FloatGrid, fog volume, σ per local unit = σ_model * model_per_local, background 0) and
// "color" (Vec3SGrid, LINEAR RGB); index -> local: voxel centres at -1 + (index + 0.5) * 2 / dims.
void write_vdb(const std::filesystem::path& path, const BakedGrid& grid);
// The same two grids converted to NanoVDB (float and Vec3f), both in one file, uncompressed.
void write_nvdb(const std::filesystem::path& path, const BakedGrid& grid);
// Dense float32 R, G, B (sRGB-encoded, instant-ngp's convention), σ per MODEL unit; x fastest, rows from the
// top (largest j first), then k. Voxels not baked are written as 0.
void write_raw(const std::filesystem::path& path, const BakedGrid& grid);

}  // namespace npt::bake
