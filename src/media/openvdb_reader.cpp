#include "media/openvdb_reader.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <spdlog/spdlog.h>

#include <cstdint>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/memory.h"
#include "media/openvdb_layout.h"

namespace npt::media {
namespace {

// local -> index of the dense array: OpenVDB's own world->index map (its "world" is the cube's local space),
// shifted so that the bbox's min voxel is index 0. Built from the map's images of the origin and the unit
// vectors, so that we never depend on OpenVDB's row-vector matrix layout.
Affine3 local_to_dense_index(const openvdb::math::Transform& xf, const openvdb::Coord& origin) {
    const openvdb::Vec3d o = xf.worldToIndex(openvdb::Vec3d(0.0));
    Affine3 a;
    for (int c = 0; c < 3; ++c) {
        openvdb::Vec3d e(0.0);
        e[c] = 1.0;
        const openvdb::Vec3d col = xf.worldToIndex(e) - o;
        for (int r = 0; r < 3; ++r) a.m[3 * r + c] = float(col[r]);
    }
    a.t = Vec3(float(o[0] - origin.x()), float(o[1] - origin.y()), float(o[2] - origin.z()));
    return a;
}

std::string grid_names(openvdb::io::File& file) {
    std::string names;
    for (auto it = file.beginName(); it != file.endName(); ++it)
        names += (names.empty() ? "'" : ", '") + *it + "'";
    return names.empty() ? "none" : names;
}

template <typename GridT>
typename GridT::Ptr read_typed(openvdb::io::File& file, const std::string& where, const std::string& name,
                               const char* expected) {
    openvdb::GridBase::Ptr base = file.readGrid(name);
    auto grid = openvdb::gridPtrCast<GridT>(base);
    if (!grid)
        throw Error(where + ": grid '" + name + "' is a " + base->valueType() + " grid, expected " +
                    expected);
    return grid;
}

// Writes every active value of `grid` (voxels and tiles) that falls inside `bbox` into `out` (dense, x
// fastest, index 0 = bbox.min()); `convert` turns a grid value into the array's element.
template <typename GridT, typename T, typename Convert>
void scatter_active(const GridT& grid, const openvdb::CoordBBox& bbox, std::vector<T>& out, Convert convert) {
    const openvdb::Coord lo = bbox.min(), dim = bbox.dim();
    auto put = [&](const openvdb::Coord& c, const auto& v) {
        const size_t idx =
            (size_t(c.z() - lo.z()) * size_t(dim.y()) + size_t(c.y() - lo.y())) * size_t(dim.x()) +
            size_t(c.x() - lo.x());
        out[idx] = convert(v);
    };
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        if (it.isVoxelValue()) {
            if (bbox.isInside(it.getCoord())) put(it.getCoord(), *it);
            continue;
        }
        openvdb::CoordBBox tile = it.getBoundingBox();
        tile.intersect(bbox);
        if (tile.empty()) continue;
        for (auto c = tile.begin(); c; ++c) put(*c, *it);
    }
}

Vec3 to_vec3(const openvdb::Vec3s& v) { return Vec3(v[0], v[1], v[2]); }

}  // namespace

VolumeGrid read_openvdb_grid(const std::filesystem::path& path, size_t max_voxels) {
    ensure_openvdb_initialized();
    const std::string where = path.string();
    try {
        check_openvdb_layout(where);
        openvdb::io::File file(where);
        file.open(false);  // no delayed loading: the file is read now and not kept mapped
        if (!file.hasGrid("density"))
            throw Error(where + ": no grid 'density' (the file has: " + grid_names(file) + ")");
        auto density = read_typed<openvdb::FloatGrid>(file, where, "density", "float");
        openvdb::Vec3SGrid::Ptr color;
        if (file.hasGrid("color")) color = read_typed<openvdb::Vec3SGrid>(file, where, "color", "vec3s");
        file.close();

        if (density->background() != 0.0f)
            throw Error(where + ": grid 'density': non-zero background is not supported (background " +
                        std::to_string(density->background()) + ")");
        if (!density->transform().isLinear())
            throw Error(where + ": grid 'density': a non-linear (frustum) transform is not supported");
        const openvdb::CoordBBox bbox = density->evalActiveVoxelBoundingBox();
        if (bbox.empty()) throw Error(where + ": grid 'density' has no active voxels");
        // In 64 bits: a box from -2^31 to 2^31 - 1 is 2^32 voxels wide, more than bbox.dim()'s int32.
        int64_t extent[3];
        for (int c = 0; c < 3; ++c) extent[c] = int64_t(bbox.max()[c]) - int64_t(bbox.min()[c]) + 1;
        check_dense_size(where, "grid 'density': active bounding box", double(extent[0]), double(extent[1]),
                         double(extent[2]), max_voxels);
        const openvdb::Coord dim{int(extent[0]), int(extent[1]), int(extent[2])};
        const size_t n = size_t(extent[0]) * size_t(extent[1]) * size_t(extent[2]);

        VolumeGrid g;
        g.source = where;
        g.nx = dim.x();
        g.ny = dim.y();
        g.nz = dim.z();
        g.local_to_index = local_to_dense_index(density->transform(), bbox.min());
        with_memory_context(where + ": grid 'density': a dense " + std::to_string(dim.x()) + "x" +
                                std::to_string(dim.y()) + "x" + std::to_string(dim.z()) + " grid",
                            double(n) * (4.0 + 12.0), "use a coarser grid", [&] {
                                g.density.assign(n, 0.0f);
                                g.color.reserve(n);  // density and colour together, or neither
                            });
        scatter_active(*density, bbox, g.density, [](float v) { return v; });

        if (!color) {
            spdlog::warn("{}: no grid 'color': the volume is white", where);
            g.color.assign(n, Vec3(1.0f));
        } else if (color->transform() == density->transform()) {
            g.color.assign(n, to_vec3(color->background()));
            scatter_active(*color, bbox, g.color, to_vec3);
        } else {
            // Different voxels: sample the colour field trilinearly at each density voxel's position.
            g.color.resize(n);
            const auto& dxf = density->transform();
            const auto& cxf = color->transform();
            auto acc = color->getConstAccessor();
            size_t idx = 0;
            for (int k = bbox.min().z(); k <= bbox.max().z(); ++k)
                for (int j = bbox.min().y(); j <= bbox.max().y(); ++j)
                    for (int i = bbox.min().x(); i <= bbox.max().x(); ++i) {
                        const openvdb::Vec3d p = cxf.worldToIndex(dxf.indexToWorld(openvdb::Coord(i, j, k)));
                        g.color[idx++] = to_vec3(openvdb::tools::BoxSampler::sample(acc, p));
                    }
        }
        return g;
    } catch (const Error&) {
        throw;
    } catch (const std::bad_alloc&) {
        // OpenVDB 10 allocates what a size field in the file says before reading it: a corrupt one asks for
        // up to 2^63 bytes. (Our own dense arrays report their size above.)
        throw Error(where +
                    ": cannot read OpenVDB file: OpenVDB asked for more memory than this machine could "
                    "allocate (a corrupt size field, or a grid too large for this machine)");
    } catch (const std::exception& e) {
        // openvdb::Exception ("IoError: ..."), or std::ios/bad_alloc from a corrupt stream: one line.
        std::string msg = e.what();
        for (char& c : msg)
            if (c == '\n') c = ' ';
        throw Error(where + ": cannot read OpenVDB file: " + msg);
    }
}

void ensure_openvdb_initialized() {
    // A function-local static is initialised exactly once even when loaders run on several threads.
    static const bool initialised = [] {
        openvdb::initialize();
        return true;
    }();
    (void)initialised;
}

}  // namespace npt::media
