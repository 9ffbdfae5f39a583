// OpenVDB and NanoVDB writers (grid_writers.h): both build the same two OpenVDB grids; NanoVDB converts them.
// clang-format off
#include "media/nanovdb_headers.h"  // first: NanoVDB with its own asserts off
// clang-format on
#include <openvdb/openvdb.h>

#include <exception>
#include <fstream>
#include <vector>

#include "bake/grid_writers.h"
#include "bake/nanovdb_convert.h"
#include "core/error.h"
#include "core/srgb.h"
#include "core/temp_file.h"
#include "media/openvdb_reader.h"

namespace npt::bake {
namespace {

struct VdbGrids {
    openvdb::FloatGrid::Ptr density;
    openvdb::Vec3SGrid::Ptr color;
};

VdbGrids make_grids(const BakedGrid& grid) {
    media::ensure_openvdb_initialized();
    const BakeLayout& L = grid.layout;
    // index -> local: local = -1 + (index + 0.5) * 2 / dims, per axis (the crop fills the cube, as placed).
    auto xf = openvdb::math::Transform::createLinearTransform(1.0);
    const double span = double(k_local_max - k_local_min);
    xf->postScale(openvdb::Vec3d(span / L.dims[0], span / L.dims[1], span / L.dims[2]));
    xf->postTranslate(openvdb::Vec3d(k_local_min + 0.5 * span / L.dims[0],
                                     k_local_min + 0.5 * span / L.dims[1],
                                     k_local_min + 0.5 * span / L.dims[2]));
    VdbGrids g;
    g.density = openvdb::FloatGrid::create(0.0f);
    g.density->setName("density");
    g.density->setGridClass(openvdb::GRID_FOG_VOLUME);
    g.density->setTransform(xf);
    g.color = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    g.color->setName("color");
    g.color->setTransform(xf->copy());
    auto dacc = g.density->getAccessor();
    auto cacc = g.color->getAccessor();
    for (size_t v = 0; v < grid.size(); ++v) {
        const openvdb::Coord c(grid.coords[3 * v], grid.coords[3 * v + 1], grid.coords[3 * v + 2]);
        if (grid.has_density[v]) dacc.setValue(c, grid.sigma[v] * L.model_per_local);
        // Linear RGB: our readers and Blender treat a VDB colour grid as linear.
        const Rgb s = grid.color[v];
        cacc.setValue(c, openvdb::Vec3s(srgb_to_linear(s.x), srgb_to_linear(s.y), srgb_to_linear(s.z)));
    }
    g.density->insertMeta("nerfpt_sigma_scale", openvdb::FloatMetadata(L.model_per_local));
    // What the colour grid holds (bake_grid.h, BakeColour): Blender's import shades an albedo grid as a
    // scattering volume and a radiance grid as emission.
    g.color->insertMeta("nerfpt_colour",
                        openvdb::StringMetadata(grid.colour == BakeColour::albedo ? "albedo" : "radiance"));
    return g;
}

// OpenVDB and NanoVDB report failures as exceptions with multi-line texts: one line, naming the file.
[[noreturn]] void rethrow(const std::filesystem::path& path, const std::exception& e) {
    std::string msg = e.what();
    for (char& c : msg)
        if (c == '\n') c = ' ';
    throw Error(path.string() + ": cannot write: " + msg);
}

}  // namespace

void write_vdb(const std::filesystem::path& path, const BakedGrid& grid) {
    const VdbGrids g = make_grids(grid);
    TempFile tmp(path);
    try {
        openvdb::io::File file(tmp.path().string());
        file.write(openvdb::GridCPtrVec{g.density, g.color});
        file.close();
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        rethrow(path, e);
    }
    tmp.commit();
}

void write_nvdb(const std::filesystem::path& path, const BakedGrid& grid) {
    const VdbGrids g = make_grids(grid);
    TempFile tmp(path);
    try {
        std::vector<nanovdb::GridHandle<>> handles;
        // A full checksum (NanoVDB's default is partial: header and upper nodes only), so that the reader
        // detects a corrupted voxel too.
        handles.push_back(
            nanovdb::openToNanoVDB(*g.density, nanovdb::StatsMode::Default, nanovdb::ChecksumMode::Full));
        handles.push_back(
            nanovdb::openToNanoVDB(*g.color, nanovdb::StatsMode::Default, nanovdb::ChecksumMode::Full));
        std::ofstream out(tmp.path(), std::ios::binary | std::ios::trunc);
        if (!out) throw Error(path.string() + ": cannot write (cannot create a file in its folder)");
        nanovdb::io::writeGrids(out, handles);
        out.close();
        if (!out) throw Error(path.string() + ": write failed (disk full?)");
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        rethrow(path, e);
    }
    tmp.commit();
}

void write_nanovdb_grids(const std::filesystem::path& path, const openvdb::GridPtrVec& grids, bool full_checksum) {
    const auto checksum = full_checksum ? nanovdb::ChecksumMode::Full : nanovdb::ChecksumMode::Default;
    std::vector<nanovdb::GridHandle<>> handles;
    for (const auto& g : grids) {
        // The typed overloads: NanoVDB's GridBase::Ptr one instantiates the converter for every grid type.
        if (const auto f = openvdb::gridConstPtrCast<openvdb::FloatGrid>(g))
            handles.push_back(nanovdb::openToNanoVDB(*f, nanovdb::StatsMode::Default, checksum));
        else if (const auto v = openvdb::gridConstPtrCast<openvdb::Vec3SGrid>(g))
            handles.push_back(nanovdb::openToNanoVDB(*v, nanovdb::StatsMode::Default, checksum));
        else
            throw Error(path.string() + ": grid '" + g->getName() + "' is a " + g->valueType() +
                        " grid; only float and vec3s grids are converted");
    }
    nanovdb::io::writeGrids(path.string(), handles);
}

}  // namespace npt::bake
