#include "media/raw_grid_reader.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/image_io.h"

namespace npt::media {
namespace {

// <digits>x<digits>x<digits>, each a positive-or-zero number that fits size_t; false when the token is not
// one.
bool parse_dims_token(const std::string& token, std::array<size_t, 3>& dims, bool& overflow) {
    const char* p = token.data();
    const char* end = p + token.size();
    for (int a = 0; a < 3; ++a) {
        if (p == end || *p < '0' || *p > '9') return false;
        auto [next, ec] = std::from_chars(p, end, dims[a]);
        if (ec == std::errc::result_out_of_range) {
            overflow = true;
            return false;
        }
        p = next;
        if (a < 2) {
            if (p == end || *p != 'x') return false;
            ++p;
        }
    }
    return p == end;
}

}  // namespace

std::array<size_t, 3> parse_raw_grid_dims(const std::filesystem::path& path) {
    const std::string stem = path.stem().string();
    size_t start = 0;
    while (start <= stem.size()) {
        size_t stop = stem.find('_', start);
        if (stop == std::string::npos) stop = stem.size();
        std::array<size_t, 3> dims{};
        bool overflow = false;
        if (parse_dims_token(stem.substr(start, stop - start), dims, overflow)) return dims;
        if (overflow) throw Error(path.string() + ": grid dimensions in the file name are too large");
        start = stop + 1;
    }
    throw Error(path.string() + ": a raw grid's file name must contain its size as {W}x{H}x{D} (e.g. " +
                "256x256x256_density.bin)");
}

VolumeGrid read_raw_grid(const std::filesystem::path& path, const GridLoadOptions& options) {
    const std::string where = path.string();
    const auto [w, h, d] = parse_raw_grid_dims(path);
    if (w == 0 || h == 0 || d == 0)
        throw Error(where + ": grid size " + std::to_string(w) + "x" + std::to_string(h) + "x" +
                    std::to_string(d) + " has a zero dimension");
    check_dense_size(where, "grid size", double(w), double(h), double(d), options.max_voxels);  // clamped by the caller
    const size_t n = w * h * d;
    const Vec3 size = options.local_max - options.local_min;
    if (!(size.x > 0.0f && size.y > 0.0f && size.z > 0.0f))
        throw Error(where +
                    ": the volume's local box is empty (local_max must exceed local_min on every axis)");

    std::error_code ec;
    const uintmax_t actual = std::filesystem::file_size(path, ec);
    if (ec) throw Error(where + ": cannot read: " + ec.message());
    const uintmax_t expected = uintmax_t(n) * 16u;
    if (actual != expected)
        throw Error(where + ": a " + std::to_string(w) + "x" + std::to_string(h) + "x" + std::to_string(d) +
                    " raw grid (4 float32 per voxel) must be " + std::to_string(expected) +
                    " bytes, the file has " + std::to_string(actual));

    std::vector<float> raw(n * 4);
    std::ifstream in(path, std::ios::binary);
    if (!in || !in.read(reinterpret_cast<char*>(raw.data()), std::streamsize(expected)))
        throw Error(where + ": cannot read " + std::to_string(expected) + " bytes");
    if constexpr (std::endian::native == std::endian::big) {
        for (float& f : raw) {
            uint32_t u;
            std::memcpy(&u, &f, 4);
            u = __builtin_bswap32(u);
            std::memcpy(&f, &u, 4);
        }
    }

    VolumeGrid g;
    g.source = where;
    g.nx = int(w);
    g.ny = int(h);
    g.nz = int(d);
    g.density.resize(n);
    g.color.resize(n);
    auto decode = [&](float c) { return options.raw_color_is_srgb ? srgb_to_linear(c) : c; };
    for (size_t k = 0; k < d; ++k)
        for (size_t jf = 0; jf < h; ++jf) {
            // The file's first row is the top one (image order): our j grows with local y.
            const size_t j = h - 1 - jf;
            const float* src = raw.data() + (k * h + jf) * w * 4;
            const size_t dst = (k * h + j) * w;
            for (size_t i = 0; i < w; ++i, src += 4) {
                g.color[dst + i] = Vec3(decode(src[0]), decode(src[1]), decode(src[2]));
                g.density[dst + i] = src[3];
            }
        }

    // Cell-centred: voxel i's centre is at local_min + (i + 0.5) * size / W, so local_min -> -0.5, local_max
    // -> W - 0.5. Computed per axis: x = s * p + t with s = W / size, t = -local_min * s - 0.5.
    const Vec3 s(float(w) / size.x, float(h) / size.y, float(d) / size.z);
    g.local_to_index.m[0] = s.x;
    g.local_to_index.m[4] = s.y;
    g.local_to_index.m[8] = s.z;
    g.local_to_index.t = Vec3(-options.local_min.x * s.x - 0.5f, -options.local_min.y * s.y - 0.5f,
                              -options.local_min.z * s.z - 0.5f);
    return g;
}

}  // namespace npt::media
