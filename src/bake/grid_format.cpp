// Format names, extensions and the raw grid's file name (grid_writers.h).
#include <fmt/format.h>

#include <algorithm>

#include "bake/grid_writers.h"
#include "core/error.h"
#include "media/raw_grid_reader.h"
#include "media/volume_grid.h"

namespace npt::bake {
namespace {

std::string lower_extension(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

const char* extension_of(GridFormat f) {
    switch (f) {
        case GridFormat::vdb:
            return ".vdb";
        case GridFormat::nvdb:
            return ".nvdb";
        case GridFormat::raw:
            return ".bin";
    }
    return "";
}

}  // namespace

GridFormat grid_format_from_name(const std::string& name) {
    if (name == "vdb") return GridFormat::vdb;
    if (name == "nvdb") return GridFormat::nvdb;
    if (name == "raw") return GridFormat::raw;
    throw Error("--format '" + name + "': unknown format (available: vdb, nvdb, raw)");
}

GridFormat grid_format_from_path(const std::filesystem::path& path) {
    const std::string ext = lower_extension(path);
    if (ext == ".vdb") return GridFormat::vdb;
    if (ext == ".nvdb") return GridFormat::nvdb;
    if (ext == ".bin") return GridFormat::raw;
    throw Error("--output '" + path.string() + "': unknown grid extension '" + ext +
                "' (use .vdb, .nvdb or .bin, or give --format)");
}

void check_extension(const std::filesystem::path& path, GridFormat format) {
    if (lower_extension(path) != extension_of(format))
        throw Error("--output '" + path.string() + "': this format's files must end in " +
                    extension_of(format) + " (the renderer picks the reader by extension)");
}

std::filesystem::path raw_output_path(const std::filesystem::path& out, const BakeLayout& layout) {
    const std::string size = fmt::format("{}x{}x{}", layout.dims[0], layout.dims[1], layout.dims[2]);
    try {
        const auto dims = media::parse_raw_grid_dims(out);
        if (dims[0] == size_t(layout.dims[0]) && dims[1] == size_t(layout.dims[1]) &&
            dims[2] == size_t(layout.dims[2]))
            return out;
    } catch (const Error&) {
        return out.parent_path() / (size + "_" + out.filename().string());  // the name has no size yet
    }
    throw Error("--output '" + out.string() + "': the name gives a raw grid size other than the baked " +
                size + " (drop the size from the name; it is added)");
}

void check_raw_size(const BakeLayout& layout) {
    if (layout.voxel_count() > media::k_max_dense_voxels)
        throw Error(fmt::format(
            "--res: a raw grid is dense and {}x{}x{} = {} voxels is more than the {} the "
            "renderer loads; use a lower --res or .vdb/.nvdb",
            layout.dims[0], layout.dims[1], layout.dims[2], layout.voxel_count(), media::k_max_dense_voxels));
}

}  // namespace npt::bake
