#include "media/nanovdb_reader.h"

// clang-format off
#include "media/nanovdb_headers.h"  // first: NanoVDB with its own asserts off
// clang-format on
#include <spdlog/spdlog.h>

#include <array>
#include <cctype>
#include <exception>
#include <string>
#include <type_traits>
#include <vector>

#include "core/error.h"
#include "core/memory.h"
#include "media/nanovdb_grid_check.h"
#include "media/nanovdb_layout.h"

namespace npt::media {
namespace {

// index = a * world + b, in double, read off the grid's own world->index map at the origin and unit vectors.
struct MapD {
    std::array<double, 9> a{};
    std::array<double, 3> b{};
    bool operator==(const MapD&) const = default;
};

template <typename GridT>
MapD world_to_index(const GridT& grid) {
    MapD m;
    const nanovdb::Vec3d o = grid.worldToIndex(nanovdb::Vec3d(0.0));
    for (int c = 0; c < 3; ++c) {
        nanovdb::Vec3d e(0.0);
        e[c] = 1.0;
        const nanovdb::Vec3d col = grid.worldToIndex(e) - o;
        for (int r = 0; r < 3; ++r) m.a[3 * r + c] = col[r];
    }
    for (int r = 0; r < 3; ++r) m.b[r] = o[r];
    return m;
}

// Lower case, as OpenVDB spells its value types ("float", "vec3s"), so messages read alike for both formats.
std::string type_name(nanovdb::GridType type) {
    // The type comes from the file: NanoVDB's toStr indexes its table with it unchecked (a fuzz finding).
    if (uint32_t(type) >= uint32_t(nanovdb::GridType::End))
        return "unknown (" + std::to_string(uint32_t(type)) + ")";
    std::string s = nanovdb::toStr(type);
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

std::string grid_names(const std::vector<nanovdb::io::GridMetaData>& metas) {
    std::string names;
    for (const auto& m : metas) names += (names.empty() ? "'" : ", '") + m.gridName + "'";
    return names.empty() ? "none" : names;
}

// Reads grid `name` of value type ValueT, after checking from the file's metadata that it is there, of the
// right type, uncompressed and no larger than the file (so that a corrupt header cannot make us allocate
// gigabytes), then checks every offset and count in the grid against its bytes (nanovdb_grid_check.h:
// NanoVDB's checksum and accessors trust them) before NanoVDB validates the structure and the checksum.
template <typename ValueT>
nanovdb::GridHandle<> read_typed(const std::string& where, const nanovdb::io::GridMetaData& meta,
                                 nanovdb::GridType type, uintmax_t file_size) {
    const std::string grid = "grid '" + meta.gridName + "'";
    if (meta.gridType != type)
        throw Error(where + ": " + grid + " is a " + type_name(meta.gridType) + " grid, expected " +
                    type_name(type));
    if (meta.codec != nanovdb::io::Codec::NONE)
        throw Error(where + ": " + grid + " is compressed (" + nanovdb::io::toStr(meta.codec) +
                    "); only uncompressed NanoVDB files are supported");
    if (meta.gridSize > file_size || meta.gridSize != meta.fileSize)
        throw Error(where + ": " + grid + " claims " + std::to_string(meta.gridSize) +
                    " bytes in a file of " + std::to_string(file_size) + " bytes (corrupt file)");
    auto handle = nanovdb::io::readGrid<nanovdb::HostBuffer>(where, meta.gridName);
    check_nanovdb_grid(where, meta.gridName, handle.data(), handle.size(),
                       std::is_same_v<ValueT, float> ? NanoValueType::f32 : NanoValueType::vec3f);
    const auto* g = handle.template grid<ValueT>();
    if (!g || !nanovdb::isValid(*g, true, false))
        throw Error(where + ": " + grid + " is corrupt (its structure or checksum does not match)");
    // isValid checks the checksum the file carries. NanoVDB's default (partial) covers the header and upper
    // nodes only, so a flipped voxel value goes unnoticed: say so once per grid.
    const nanovdb::ChecksumMode mode = nanovdb::GridChecksum(g->checksum()).mode();
    if (mode != nanovdb::ChecksumMode::Full)
        spdlog::warn(
            "{}: {} carries {} checksum: corrupted voxel values cannot be detected (nerfpt bake writes a "
            "full one)",
            where, grid, mode == nanovdb::ChecksumMode::Partial ? "only a partial" : "no");
    return handle;
}

// Calls fn(coord, dense index) over the box, x fastest. NanoVDB 10 has no active-value iterators; a cached
// accessor over the dense box is simple, fast enough at the sizes we allow, and handles tiles as well as
// voxels.
template <typename Fn>
void for_each_voxel(const nanovdb::Coord& lo, const nanovdb::Coord& hi, Fn&& fn) {
    size_t idx = 0;
    for (int k = lo[2]; k <= hi[2]; ++k)
        for (int j = lo[1]; j <= hi[1]; ++j)
            for (int i = lo[0]; i <= hi[0]; ++i) fn(nanovdb::Coord(i, j, k), idx++);
}

}  // namespace

VolumeGrid read_nanovdb_grid(const std::filesystem::path& path, size_t max_voxels) {
    const std::string where = path.string();
    try {
        std::error_code ec;
        const uintmax_t file_size = std::filesystem::file_size(path, ec);
        if (ec) throw Error(where + ": cannot read: " + ec.message());
        check_nanovdb_layout(where);
        const auto metas = nanovdb::io::readGridMetaData(where);
        const nanovdb::io::GridMetaData* dmeta = nullptr;
        const nanovdb::io::GridMetaData* cmeta = nullptr;
        for (const auto& m : metas) {
            if (m.gridName == "density" && !dmeta) dmeta = &m;
            if (m.gridName == "color" && !cmeta) cmeta = &m;
        }
        if (!dmeta) throw Error(where + ": no grid 'density' (the file has: " + grid_names(metas) + ")");
        const auto dhandle = read_typed<float>(where, *dmeta, nanovdb::GridType::Float, file_size);
        nanovdb::GridHandle<> chandle;
        if (cmeta) chandle = read_typed<nanovdb::Vec3f>(where, *cmeta, nanovdb::GridType::Vec3f, file_size);
        const auto& density = *dhandle.grid<float>();

        if (density.tree().background() != 0.0f)
            throw Error(where + ": grid 'density': non-zero background is not supported (background " +
                        std::to_string(density.tree().background()) + ")");
        // NanoVDB's tree bbox is the bounding box of the active values, as OpenVDB's
        // evalActiveVoxelBoundingBox.
        const nanovdb::CoordBBox bbox = density.indexBBox();
        if (bbox.empty() || density.activeVoxelCount() == 0)
            throw Error(where + ": grid 'density' has no active voxels");
        const nanovdb::Coord lo = bbox.min(), hi = bbox.max();
        const size_t nx = size_t(int64_t(hi[0]) - lo[0] + 1), ny = size_t(int64_t(hi[1]) - lo[1] + 1),
                     nz = size_t(int64_t(hi[2]) - lo[2] + 1);
        // Each is at most 2^32: the product is compared in double (in size_t it wrapped to a small number).
        check_dense_size(where, "grid 'density': active bounding box", double(nx), double(ny), double(nz),
                         max_voxels);
        const size_t n = nx * ny * nz;

        VolumeGrid g;
        g.source = where;
        g.nx = int(nx);
        g.ny = int(ny);
        g.nz = int(nz);
        const MapD dmap = world_to_index(density);
        for (int i = 0; i < 9; ++i) g.local_to_index.m[i] = float(dmap.a[i]);
        g.local_to_index.t =
            Vec3(float(dmap.b[0] - lo[0]), float(dmap.b[1] - lo[1]), float(dmap.b[2] - lo[2]));

        with_memory_context(where + ": grid 'density': a dense " + std::to_string(nx) + "x" +
                                std::to_string(ny) + "x" + std::to_string(nz) + " grid",
                            double(n) * (4.0 + 12.0), "use a coarser grid", [&] {
                                g.density.resize(n);
                                g.color.reserve(n);  // density and colour together, or neither
                            });
        auto dacc = density.getAccessor();
        for_each_voxel(lo, hi, [&](const nanovdb::Coord& c, size_t idx) {
            g.density[idx] = dacc.isActive(c) ? dacc.getValue(c) : 0.0f;
        });
        if (!cmeta) {
            spdlog::warn("{}: no grid 'color': the volume is white", where);
            g.color.assign(n, Vec3(1.0f));
            return g;
        }
        g.color.resize(n);
        const auto& color = *chandle.grid<nanovdb::Vec3f>();
        auto cacc = color.getAccessor();
        if (world_to_index(color) == dmap) {
            const nanovdb::Vec3f bg = color.tree().background();
            for_each_voxel(lo, hi, [&](const nanovdb::Coord& c, size_t idx) {
                const nanovdb::Vec3f v = cacc.isActive(c) ? cacc.getValue(c) : bg;
                g.color[idx] = Vec3(v[0], v[1], v[2]);
            });
        } else {
            // Different voxels: sample the colour trilinearly at each density voxel's position.
            auto sampler = nanovdb::createSampler<1, decltype(cacc), false>(cacc);
            for_each_voxel(lo, hi, [&](const nanovdb::Coord& c, size_t idx) {
                const nanovdb::Vec3d p =
                    color.worldToIndex(density.indexToWorld(nanovdb::Vec3d(c[0], c[1], c[2])));
                const nanovdb::Vec3f v = sampler(p);
                g.color[idx] = Vec3(v[0], v[1], v[2]);
            });
        }
        return g;
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        // NanoVDB reports bad files with std::runtime_error, some messages spanning lines.
        std::string msg = e.what();
        for (char& ch : msg)
            if (ch == '\n' || ch == '\t') ch = ' ';
        throw Error(where + ": cannot read NanoVDB file: " + msg);
    }
}

}  // namespace npt::media
