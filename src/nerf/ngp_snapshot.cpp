#include "nerf/ngp_snapshot.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/json_file.h"
#include "nerf/ngp_hash_grid.h"

namespace npt::nerf {
namespace {

using json = nlohmann::json;

// A decompressed snapshot larger than this is refused rather than allocated (instant-ngp's largest configs
// stay well under 1 GiB); it also bounds what a hostile .ingp can make us allocate.
constexpr size_t k_max_snapshot_bytes = size_t(4) << 30;
constexpr int k_max_width = k_max_mlp_width;
constexpr int k_sh_dims = k_sh_deg4_dims;
// instant-ngp's NERF_STEPS(): the density grid stores sigma times sqrt(3) / 1024.
constexpr int k_ngp_steps = 1024;

std::string lower(std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

// Field access with errors that name the file and the dotted path of the field.
struct Fields {
    const std::string& source;

    static std::string join(const std::string& path, const char* key) {
        return path.empty() ? std::string(key) : path + "." + key;
    }

    Error error(const std::string& path, const std::string& what) const {
        return Error(source + ": '" + path + "' " + what);
    }
    const json& need(const json& j, const std::string& path, const char* key) const {
        if (!j.is_object()) throw error(path, "is not an object");
        auto it = j.find(key);
        if (it == j.end()) throw error(join(path, key), "is missing");
        return *it;
    }
    const json* find(const json& j, const char* key) const {
        if (!j.is_object()) return nullptr;
        auto it = j.find(key);
        return it == j.end() || it->is_null() ? nullptr : &*it;
    }
    const json& need_object(const json& j, const std::string& path, const char* key) const {
        const json& v = need(j, path, key);
        if (!v.is_object()) throw error(join(path, key), "is not an object");
        return v;
    }
    std::string string_or(const json& j, const std::string& path, const char* key,
                          const std::string& dflt) const {
        const json* v = find(j, key);
        if (!v) return dflt;
        if (!v->is_string()) throw error(path + "." + key, "is not a string");
        return v->get<std::string>();
    }
    int64_t int_or(const json& j, const std::string& path, const char* key, int64_t dflt, int64_t lo,
                   int64_t hi) const {
        const json* v = find(j, key);
        if (!v) return dflt;
        if (!v->is_number_integer() && !v->is_number_unsigned())
            throw error(path + "." + key, "is not an integer");
        if (v->is_number_unsigned() && v->get<uint64_t>() > uint64_t(hi))
            throw error(path + "." + key, "is " + v->dump() + ", outside [" + std::to_string(lo) + ", " +
                                              std::to_string(hi) + "]");
        const int64_t x = v->get<int64_t>();
        if (x < lo || x > hi)
            throw error(path + "." + key, "is " + std::to_string(x) + ", outside [" + std::to_string(lo) +
                                              ", " + std::to_string(hi) + "]");
        return x;
    }
    double number_or(const json& j, const std::string& path, const char* key, double dflt) const {
        const json* v = find(j, key);
        if (!v) return dflt;
        if (!v->is_number()) throw error(path + "." + key, "is not a number");
        const double x = v->get<double>();
        if (!std::isfinite(x)) throw error(path + "." + key, "is not finite");
        return x;
    }
    bool bool_or(const json& j, const std::string& path, const char* key, bool dflt) const {
        const json* v = find(j, key);
        if (!v) return dflt;
        if (!v->is_boolean()) throw error(path + "." + key, "is not a boolean");
        return v->get<bool>();
    }
    // nlohmann writes GPUMemory as MessagePack bin; a snapshot that went through JSON has {"bytes": [...]}.
    std::vector<uint8_t> binary(const json& j, const std::string& path, const char* key) const {
        const json& v = need(j, path, key);
        if (v.is_binary()) return v.get_binary();
        if (v.is_object() && v.contains("bytes") && v["bytes"].is_array()) {
            std::vector<uint8_t> out;
            out.reserve(v["bytes"].size());
            for (const json& b : v["bytes"]) {
                if (!b.is_number_unsigned() || b.get<uint64_t>() > 255)
                    throw error(path + "." + key + ".bytes", "holds a value that is not a byte");
                out.push_back(uint8_t(b.get<uint64_t>()));
            }
            return out;
        }
        throw error(path + "." + key, "is not binary data");
    }
};

std::vector<uint8_t> read_file(const std::filesystem::path& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error(path.string() + ": no such file");
    const uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec) throw Error(path.string() + ": cannot read the file size (" + ec.message() + ")");
    if (size > k_max_snapshot_bytes) throw Error(path.string() + ": larger than 4 GiB, not a NeRF snapshot");
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(path.string() + ": cannot open for reading");
    std::vector<uint8_t> bytes(static_cast<size_t>(size));
    if (size > 0 && !f.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size)))
        throw Error(path.string() + ": read error");
    return bytes;
}

bool is_gzip(const std::vector<uint8_t>& b) { return b.size() >= 2 && b[0] == 0x1f && b[1] == 0x8b; }
bool is_zlib(const std::vector<uint8_t>& b) {
    // RFC 1950 header: deflate with a window of at most 32 KiB and a check value making it a multiple of 31.
    // Such a first byte is a MessagePack integer, never the map a snapshot starts with.
    return b.size() >= 2 && (b[0] & 0x0f) == 8 && (b[0] >> 4) <= 7 &&
           ((unsigned(b[0]) << 8) | b[1]) % 31 == 0;
}

// instant-ngp writes .ingp through zstr (gzip framing); zlib framing is accepted too, as zstr reads both.
std::vector<uint8_t> inflate_all(const std::vector<uint8_t>& in, const std::string& source) {
    // zlib counts input in 32 bits; no NeRF snapshot compresses to 4 GiB.
    if (in.size() > size_t(UINT32_MAX)) throw Error(source + ": larger than 4 GiB, not a NeRF snapshot");
    z_stream zs{};
    if (inflateInit2(&zs, 15 + 32) != Z_OK) throw Error(source + ": zlib initialisation failed");
    std::vector<uint8_t> out;
    zs.next_in = const_cast<Bytef*>(in.data());
    zs.avail_in = uInt(in.size());
    int rc = Z_OK;
    while (rc != Z_STREAM_END) {
        if (out.size() >= k_max_snapshot_bytes) {
            inflateEnd(&zs);
            throw Error(source + ": decompresses to more than 4 GiB, not a NeRF snapshot");
        }
        // Grow by half (at least 1 MiB): few reallocations without trusting any size the stream claims.
        const size_t old = out.size();
        out.resize(std::min(old + std::max<size_t>(size_t(1) << 20, old / 2), k_max_snapshot_bytes));
        zs.next_out = out.data() + old;
        zs.avail_out = uInt(out.size() - old);
        rc = inflate(&zs, Z_NO_FLUSH);
        out.resize(out.size() - zs.avail_out);
        // Output space was free, so no progress means the input ran out before the end of the stream.
        if (rc == Z_BUF_ERROR && zs.avail_in == 0) {
            inflateEnd(&zs);
            throw Error(source + ": compressed data is truncated");
        }
        if (rc != Z_OK && rc != Z_STREAM_END && rc != Z_BUF_ERROR) {
            const std::string msg = zs.msg ? zs.msg : "error " + std::to_string(rc);
            inflateEnd(&zs);
            throw Error(source + ": corrupt compressed data (" + msg + ")");
        }
    }
    inflateEnd(&zs);
    return out;
}

json parse_msgpack(const std::vector<uint8_t>& bytes, const std::string& source) {
    if (bytes.empty()) throw Error(source + ": empty file");
    check_msgpack_depth(bytes.data(), bytes.size(), source);  // nlohmann's reader recurses once per level
    try {
        return json::from_msgpack(bytes);
    } catch (const json::exception& e) {
        // nlohmann's messages start with "[json.exception.parse_error.110] "; the rest is one readable line.
        std::string what = e.what();
        if (const size_t p = what.find("] "); what.rfind("[json.exception", 0) == 0 && p != std::string::npos)
            what = what.substr(p + 2);
        throw Error(source + ": not a MessagePack snapshot (" + what + ")");
    }
}

bool is_fully_fused(const std::string& otype) {
    const std::string t = lower(otype);
    return t == "fullyfusedmlp" || t == "megakernelmlp";
}

// One tiny-cuda-nn MLP as the testbed builds it: a padded input, `hidden` layers of `width`, a padded output.
struct TcnnMlp {
    int inputs_padded = 0;
    int width = 0;
    int hidden = 0;
    int outputs_padded = 0;
    size_t param_count() const {
        return size_t(width) * inputs_padded + size_t(hidden - 1) * width * width +
               size_t(outputs_padded) * width;
    }
};

int next_multiple(int x, int m) { return (x + m - 1) / m * m; }

// Reads a "network" / "rgb_network" object: the shape we can represent, refused otherwise.
TcnnMlp read_mlp(const Fields& f, const json& net, const std::string& path, int inputs_padded,
                 int n_outputs) {
    const std::string otype = f.string_or(net, path, "otype", "MLP");
    const std::string t = lower(otype);
    if (!is_fully_fused(otype) && t != "mlp" && t != "cutlassmlp")
        throw f.error(path + ".otype",
                      "is '" + otype + "'; only FullyFusedMLP and CutlassMLP networks import");
    const std::string act = f.string_or(net, path, "activation", "ReLU");
    if (lower(act) != "relu") throw f.error(path + ".activation", "is '" + act + "'; only ReLU is supported");
    const std::string out_act = f.string_or(net, path, "output_activation", "None");
    if (lower(out_act) != "none")
        throw f.error(path + ".output_activation",
                      "is '" + out_act + "'; only None is supported (the NeRF applies its own activations)");
    TcnnMlp m;
    m.inputs_padded = inputs_padded;
    m.width = int(f.int_or(net, path, "n_neurons", 128, 1, 1 << 20));
    if (m.width > k_max_width)
        throw f.error(path + ".n_neurons", "is " + std::to_string(m.width) + "; at most " +
                                               std::to_string(k_max_width) + " is supported");
    m.hidden = int(f.int_or(net, path, "n_hidden_layers", 5, 0, 1 << 20));
    if (m.hidden < 1 || m.hidden > 16)
        throw f.error(path + ".n_hidden_layers",
                      "is " + std::to_string(m.hidden) + "; 1 to 16 hidden layers are supported");
    // Both MLP kinds pad their output to a multiple of 16 (tiny-cuda-nn's REQUIRED_ALIGNMENT()).
    m.outputs_padded = next_multiple(n_outputs, 16);
    return m;
}

// The direction encoding must be SH of degree 4 over the 3 direction dims, alone or first in a Composite
// whose other members encode nothing (instant-ngp adds an Identity for the extra dims, of which we have 0).
void check_dir_encoding(const Fields& f, const json& enc, const std::string& path) {
    auto check_sh = [&](const json& sh, const std::string& p) {
        const std::string otype = f.string_or(sh, p, "otype", "");
        if (lower(otype) != "sphericalharmonics")
            throw f.error(p + ".otype",
                          "is '" + otype + "'; only SphericalHarmonics directions are supported");
        const int64_t degree = f.int_or(sh, p, "degree", 4, 0, 1 << 20);
        if (degree != 4)
            throw f.error(p + ".degree", "is " + std::to_string(degree) + "; only degree 4 is supported");
        const int64_t dims = f.int_or(sh, p, "n_dims_to_encode", 3, 0, 1 << 20);
        if (dims != 3) throw f.error(p + ".n_dims_to_encode", "is " + std::to_string(dims) + ", not 3");
    };
    const std::string otype = f.string_or(enc, path, "otype", "");
    if (lower(otype) != "composite") return check_sh(enc, path);
    const json& nested = f.need(enc, path, "nested");
    if (!nested.is_array() || nested.empty()) throw f.error(path + ".nested", "is not a non-empty array");
    check_sh(nested[0], path + ".nested[0]");
    // The other members see the extra dims only; check_dataset refuses snapshots that have any.
}

struct GridShape {
    HashGridConfig grid;        // levels, features, table size, base resolution (per_level_scale below)
    float per_level_scale = 0;  // as tiny-cuda-nn used it
    std::vector<uint32_t> level_size;  // tiny-cuda-nn's entries per level
    size_t param_count() const {
        size_t n = 0;
        for (uint32_t s : level_size) n += s;
        return n * size_t(grid.features_per_level);
    }
};

GridShape read_encoding(const Fields& f, const json& enc, float aabb_scale) {
    const std::string p = "encoding";
    const std::string otype = f.string_or(enc, p, "otype", "");
    const std::string t = lower(otype);
    if (t != "hashgrid" && t != "grid")
        throw f.error(p + ".otype", "is '" + otype + "'; only HashGrid position encodings import");
    const std::string type = f.string_or(enc, p, "type", "Hash");
    if (lower(type) != "hash") throw f.error(p + ".type", "is '" + type + "'; only Hash grids import");
    const std::string hash = f.string_or(enc, p, "hash", "CoherentPrime");
    if (lower(hash) != "coherentprime")
        throw f.error(p + ".hash", "is '" + hash + "'; only CoherentPrime (the default) matches our hash");
    const std::string interp = f.string_or(enc, p, "interpolation", "Linear");
    if (lower(interp) != "linear") throw f.error(p + ".interpolation", "is '" + interp + "'; only Linear");
    if (f.bool_or(enc, p, "fixed_point_pos", false))
        throw f.error(p + ".fixed_point_pos", "is true; unsupported");
    if (const int64_t d = f.int_or(enc, p, "n_pos_dims", 3, 0, 1 << 20); d != 3)
        throw f.error(p + ".n_pos_dims", "is " + std::to_string(d) + ", not 3");

    GridShape g;
    HashGridConfig& c = g.grid;
    c.features_per_level = int(f.int_or(enc, p, "n_features_per_level", 2, 1, 8));
    if (c.features_per_level != 1 && c.features_per_level != 2 && c.features_per_level != 4 &&
        c.features_per_level != 8)
        throw f.error(p + ".n_features_per_level",
                      "is " + std::to_string(c.features_per_level) + "; tiny-cuda-nn has 1, 2, 4 or 8");
    if (f.find(enc, "n_features")) {
        const int64_t nf = f.int_or(enc, p, "n_features", 0, 1, 256);
        if (nf % c.features_per_level != 0)
            throw f.error(p + ".n_features", "is not a multiple of n_features_per_level");
        c.levels = int(nf / c.features_per_level);
    } else {
        c.levels = int(f.int_or(enc, p, "n_levels", 16, 1, 256));
    }
    if (c.levels > 32) throw f.error(p + ".n_levels", "is " + std::to_string(c.levels) + "; at most 32");
    if (c.output_dims() > k_max_width)
        throw f.error(p + ".n_levels", "times n_features_per_level is " + std::to_string(c.output_dims()) +
                                           "; at most " + std::to_string(k_max_width) +
                                           " features are supported");
    c.log2_table_size = int(f.int_or(enc, p, "log2_hashmap_size", 19, 10, 26));
    // The testbed derives what the config leaves out (testbed.cu, reset_network): base resolution from its
    // own default of 2^15 entries, the per-level scale from a finest resolution of 2048 * aabb_scale.
    c.base_resolution = int(f.int_or(enc, p, "base_resolution", 0, 0, 1 << 16));
    if (c.base_resolution == 0)
        c.base_resolution = 1 << (f.int_or(enc, p, "log2_hashmap_size", 15, 0, 30) / 3);
    if (c.base_resolution < 2) throw f.error(p + ".base_resolution", "is below 2");
    double b = f.number_or(enc, p, "per_level_scale", 0.0);
    if (b <= 0.0) {
        b = c.levels > 1
                ? std::exp(std::log(2048.0f * aabb_scale / float(c.base_resolution)) / float(c.levels - 1))
                : 2.0f;  // tiny-cuda-nn's default; irrelevant for one level
    }
    g.per_level_scale = float(b);
    if (c.levels > 1 && !(g.per_level_scale >= 1.0f))
        throw f.error(p + ".per_level_scale", "is below 1; unsupported");
    g.level_size.resize(size_t(c.levels));
    for (int l = 0; l < c.levels; ++l) {
        const TcnnLevel tl = tcnn_level(c, g.per_level_scale, l);
        g.level_size[size_t(l)] = tl.size;
    }
    return g;
}

// Our config derives per_level_scale from finest_resolution; find the finest resolution that gives exactly
// the snapshot's float, so that every level's scale (and so every vertex) is bit-identical.
float finest_for_scale(const NerfConfig& base, float aabb_scale, float target, bool& exact) {
    NerfConfig c = base;
    const int levels = c.encoding.grid.levels;
    if (levels <= 1) {
        exact = true;
        return float(c.encoding.grid.base_resolution);
    }
    float f = float(c.encoding.grid.base_resolution * std::pow(double(target), levels - 1) / aabb_scale);
    auto scale_for = [&](float finest) {
        c.encoding.finest_resolution = finest;
        return make_layout(c, aabb_scale).grid.per_level_scale;
    };
    float best = f, best_err = std::fabs(scale_for(f) - target);
    float up = f, down = f;
    for (int i = 0; i < 4096 && best_err > 0.0f; ++i) {
        up = std::nextafter(up, INFINITY);
        down = std::nextafter(down, 0.0f);
        for (float cand : {up, down}) {
            const float err = std::fabs(scale_for(cand) - target);
            if (err < best_err) best = cand, best_err = err;
        }
    }
    exact = best_err == 0.0f;
    return best;
}

std::vector<float> decode_params(const Fields& f, const json& snap, size_t expected) {
    const std::vector<uint8_t> bin = f.binary(snap, "snapshot", "params_binary");
    std::string type = f.string_or(snap, "snapshot", "params_type", "");
    if (type.empty()) type = bin.size() == expected * 4 ? "float" : "__half";  // older snapshots: half
    size_t elem = 0;
    if (type == "__half")
        elem = 2;
    else if (type == "float")
        elem = 4;
    else
        throw f.error("snapshot.params_type", "is '" + type + "'; expected __half or float");
    if (bin.size() % elem != 0)
        throw f.error("snapshot.params_binary", "has " + std::to_string(bin.size()) +
                                                    " bytes, not a whole number of " + type + " values");
    const size_t n = bin.size() / elem;
    if (const json* np = f.find(snap, "n_params")) {
        if (!np->is_number_unsigned() || np->get<uint64_t>() != n)
            throw f.error("snapshot.n_params",
                          "is " + np->dump() + " but params_binary holds " + std::to_string(n));
    }
    if (n != expected)
        throw f.error(
            "snapshot.params_binary",
            "holds " + std::to_string(n) + " parameters; the config needs " + std::to_string(expected));
    std::vector<float> out(n);
    for (size_t i = 0; i < n; ++i) {
        if (elem == 2) {
            uint16_t h;
            std::memcpy(&h, &bin[i * 2], 2);
            out[i] = ngp_half_to_float(h);
        } else {
            std::memcpy(&out[i], &bin[i * 4], 4);
        }
        if (!std::isfinite(out[i]))
            throw f.error("snapshot.params_binary", "parameter " + std::to_string(i) + " is not finite");
    }
    return out;
}

// tiny-cuda-nn stores each layer row-major [outputs][inputs] over the padded sizes; we keep the rows and
// columns that carry information. Dropped input columns see zeros (the grid pads with 0) and dropped output
// rows are never read (the colour MLP's rows 3..15), so nothing is lost.
void copy_mlp(const TcnnMlp& t, const MlpShape& ours, const float* src, float* dst) {
    size_t src_off = 0;
    for (int l = 0; l < ours.layer_count(); ++l) {
        const int t_in = l == 0 ? t.inputs_padded : t.width;
        const int t_out = l == ours.hidden_layers ? t.outputs_padded : t.width;
        const int ni = ours.layer_inputs(l), no = ours.layer_outputs(l);
        float* w = dst + ours.layer_offset(l);
        for (int o = 0; o < no; ++o)
            for (int i = 0; i < ni; ++i) w[size_t(o) * ni + i] = src[src_off + size_t(o) * t_in + i];
        src_off += size_t(t_in) * t_out;
    }
}

Mat4 world_to_model_from(const Fields& f, const json& dataset, bool has_dataset,
                         std::vector<std::string>& notes) {
    if (!has_dataset) {
        notes.push_back(
            "the snapshot has no 'snapshot.nerf.dataset': world_to_model uses instant-ngp's defaults "
            "(scale 1, offset 0)");
    }
    const double scale = has_dataset ? f.number_or(dataset, "snapshot.nerf.dataset", "scale", 1.0) : 1.0;
    Vec3 offset(0.0f);
    if (const json* o = has_dataset ? f.find(dataset, "offset") : nullptr) {
        if (!o->is_array() || o->size() != 3 || !(*o)[0].is_number() || !(*o)[1].is_number() ||
            !(*o)[2].is_number())
            throw f.error("snapshot.nerf.dataset.offset", "is not an array of 3 numbers");
        offset = Vec3((*o)[0].get<float>(), (*o)[1].get<float>(), (*o)[2].get<float>());
    }
    if (!(scale > 0.0) || !std::isfinite(offset.x + offset.y + offset.z))
        throw f.error("snapshot.nerf.dataset.scale", "must be positive and the offset finite");
    if (has_dataset && f.bool_or(dataset, "snapshot.nerf.dataset", "from_mitsuba", false)) {
        // Mitsuba scenes skip the axis cycle (nerf_loader.h, nerf_position_to_ngp).
        Mat4 m;
        const float s = float(scale);
        m.m = {{{s, 0, 0, offset.x}, {0, s, 0, offset.y}, {0, 0, s, offset.z}, {0, 0, 0, 1}}};
        return m;
    }
    return ngp_world_to_model(float(scale), offset);
}

}  // namespace

float ngp_half_to_float(uint16_t h) {
    const uint32_t sign = uint32_t(h & 0x8000u) << 16;
    const uint32_t exp = (h >> 10) & 0x1fu;
    uint32_t mant = h & 0x3ffu;
    uint32_t bits;
    if (exp == 0) {
        if (mant == 0) {
            bits = sign;
        } else {  // subnormal: normalise
            int e = -1;
            do {
                ++e;
                mant <<= 1;
            } while ((mant & 0x400u) == 0);
            bits = sign | (uint32_t(127 - 15 - e) << 23) | ((mant & 0x3ffu) << 13);
        }
    } else if (exp == 31) {
        bits = sign | 0x7f800000u | (mant << 13);
    } else {
        bits = sign | ((exp + 127 - 15) << 23) | (mant << 13);
    }
    float out;
    std::memcpy(&out, &bits, 4);
    return out;
}

uint32_t ngp_morton3(uint32_t x, uint32_t y, uint32_t z) {
    auto spread = [](uint32_t v) {
        uint32_t r = 0;
        for (int b = 0; b < 10; ++b) r |= ((v >> b) & 1u) << (3 * b);
        return r;
    };
    return spread(x) | (spread(y) << 1) | (spread(z) << 2);
}

std::vector<float> ngp_density_grid_to_occupancy(const std::vector<float>& ngp, int cascades, int resolution,
                                                 const std::string& source) {
    const size_t r = size_t(resolution), cells = r * r * r;
    if (resolution < 1 || resolution > 1024 || (resolution & (resolution - 1)) != 0)
        throw Error(source + ": 'snapshot.density_grid_size' is " + std::to_string(resolution) +
                    "; a power of two up to 1024 is needed for Morton order");
    if (ngp.size() != cells * size_t(cascades))
        throw Error(source + ": 'snapshot.density_grid_binary' has " + std::to_string(ngp.size()) +
                    " cells; expected " + std::to_string(cascades) + " cascades of " +
                    std::to_string(resolution) + "^3");
    std::vector<float> out(ngp.size());
    for (size_t c = 0; c < size_t(cascades); ++c)
        for (uint32_t z = 0; z < r; ++z)
            for (uint32_t y = 0; y < r; ++y)
                for (uint32_t x = 0; x < r; ++x) {
                    const float v = ngp[c * cells + ngp_morton3(x, y, z)];
                    if (std::isnan(v) || std::isinf(v))
                        throw Error(source + ": 'snapshot.density_grid_binary' cell " +
                                    std::to_string(c * cells + ngp_morton3(x, y, z)) + " is not finite");
                    // Negative marks cells no training camera sees; instant-ngp never marks them occupied.
                    out[c * cells + x + y * r + size_t(z) * r * r] = std::max(v, 0.0f);
                }
    return out;
}

NgpImport import_ngp_snapshot(const std::filesystem::path& path) {
    return import_ngp_snapshot(read_file(path), path.string());
}

NgpImport import_ngp_snapshot(const std::vector<uint8_t>& file_bytes, const std::string& source) {
    const Fields f{source};
    const json root = parse_msgpack(
        is_gzip(file_bytes) || is_zlib(file_bytes) ? inflate_all(file_bytes, source) : file_bytes, source);
    if (!root.is_object()) throw Error(source + ": not an instant-ngp snapshot (the top level is not a map)");
    const json& snap = f.need_object(root, "", "snapshot");
    NgpImport result;

    const std::string mode = f.string_or(snap, "snapshot", "mode", "Nerf");
    if (lower(mode) != "nerf")
        throw f.error("snapshot.mode", "is '" + mode + "'; only NeRF snapshots import");
    if (f.int_or(snap, "snapshot", "version", 0, 0, 1 << 20) < 1)
        throw f.error("snapshot.version",
                      "is missing or 0: an old format instant-ngp itself no longer loads");
    result.training_step = uint64_t(f.int_or(snap, "snapshot", "training_step", 0, 0, INT64_MAX));

    const json& nerf = f.need_object(snap, "snapshot", "nerf");
    const json* dataset = f.find(nerf, "dataset");
    if (dataset && !dataset->is_object()) throw f.error("snapshot.nerf.dataset", "is not an object");
    int64_t aabb_scale_i = f.int_or(nerf, "snapshot.nerf", "aabb_scale", 0, 0, 1 << 20);
    if (aabb_scale_i == 0 && dataset)
        aabb_scale_i = f.int_or(*dataset, "snapshot.nerf.dataset", "aabb_scale", 0, 0, 1 << 20);
    if (aabb_scale_i == 0) throw f.error("snapshot.nerf.aabb_scale", "is missing");
    const float aabb_scale = float(aabb_scale_i);
    if (dataset) {
        if (f.bool_or(*dataset, "snapshot.nerf.dataset", "is_hdr", false))
            throw f.error("snapshot.nerf.dataset.is_hdr",
                          "is true: HDR NeRFs use an exp colour activation, ours is sigmoid");
        if (const int64_t e =
                f.int_or(*dataset, "snapshot.nerf.dataset", "n_extra_learnable_dims", 0, 0, 1 << 20);
            e != 0)
            throw f.error("snapshot.nerf.dataset.n_extra_learnable_dims",
                          "is " + std::to_string(e) + "; per-image latent codes are not supported");
    }
    // Snapshots do not record the activations: instant-ngp's defaults (exp density; sigmoid colour unless
    // is_hdr, refused above) are ours.

    // The config: encoding, density network ("network"), direction encoding, colour network.
    const GridShape grid = read_encoding(f, f.need_object(root, "", "encoding"), aabb_scale);
    const json& net = f.need_object(root, "", "network");
    const int density_outputs = int(f.int_or(net, "network", "n_output_dims", 16, 1, 1 << 20));
    if (density_outputs % 16 != 0 || density_outputs + k_sh_dims > k_max_width)
        throw f.error("network.n_output_dims",
                      "is " + std::to_string(density_outputs) + "; a multiple of 16 up to 112 is supported");
    // The grid's output is padded to 16 for the fully fused MLP and to 8 otherwise (nerf_network.h).
    const int pos_align = is_fully_fused(f.string_or(net, "network", "otype", "MLP")) ? 16 : 8;
    const TcnnMlp density =
        read_mlp(f, net, "network", next_multiple(grid.grid.output_dims(), pos_align), density_outputs);
    check_dir_encoding(f, f.need_object(root, "", "dir_encoding"), "dir_encoding");
    // The colour MLP reads [density outputs, SH], padded to 16; both are multiples of 16 here, so no padding.
    const TcnnMlp color = read_mlp(f, f.need_object(root, "", "rgb_network"), "rgb_network",
                                   next_multiple(density_outputs + k_sh_dims, 16), 3);

    NerfConfig config;
    config.encoding.grid = grid.grid;
    config.encoding.sh_degree = 4;
    config.density_mlp = {density.hidden, density.width, density_outputs};
    config.color_mlp = {color.hidden, color.width, 3};
    config.march.max_steps = k_ngp_steps;
    bool scale_exact = false;
    config.encoding.finest_resolution =
        finest_for_scale(config, aabb_scale, grid.per_level_scale, scale_exact);
    if (!scale_exact)
        throw f.error("encoding.per_level_scale", "cannot be reproduced exactly by our finest_resolution");

    // The occupancy grid.
    const int64_t grid_res = f.int_or(snap, "snapshot", "density_grid_size", 128, 1, 1024);
    config.occupancy.resolution = int(grid_res);
    // Our own validation (ranges of every field), with messages naming our config's fields.
    config = config_from_json(config_to_json(config), source + " (converted config)");

    NerfModel& m = result.model;
    m.config = config;
    m.aabb_scale = aabb_scale;
    m.world_to_model = world_to_model_from(f, dataset ? *dataset : json(), dataset != nullptr, result.notes);
    m.occupancy = OccupancyGrid(cascades_for_aabb_scale(aabb_scale), config.occupancy.resolution);
    {
        const std::vector<uint8_t> bin = f.binary(snap, "snapshot", "density_grid_binary");
        if (bin.size() % 2 != 0)
            throw f.error("snapshot.density_grid_binary", "has an odd number of bytes (fp16 expected)");
        if (!bin.empty()) {
            std::vector<float> ngp(bin.size() / 2);
            for (size_t i = 0; i < ngp.size(); ++i) {
                uint16_t h;
                std::memcpy(&h, &bin[i * 2], 2);
                ngp[i] = ngp_half_to_float(h);
            }
            m.occupancy.set_density(
                ngp_density_grid_to_occupancy(ngp, m.occupancy.cascades(), m.occupancy.resolution(), source),
                config.occupancy.threshold);
        } else {
            result.notes.push_back(
                "the snapshot's density grid is empty (never trained): every cell starts occupied");
        }
    }

    // The parameters: density MLP, colour MLP, hash grid (nerf_network.h, set_params_impl).
    const NerfLayout layout = m.layout();
    const size_t expected = density.param_count() + color.param_count() + grid.param_count();
    const std::vector<float> src = decode_params(f, snap, expected);
    m.params.assign(layout.total, 0.0f);
    copy_mlp(density, layout.density, src.data(), m.params.data() + layout.density_offset);
    copy_mlp(color, layout.color, src.data() + density.param_count(), m.params.data() + layout.color_offset);
    result.levels = convert_hash_grid(layout.grid, grid.per_level_scale,
                                      src.data() + density.param_count() + color.param_count(), m.occupancy,
                                      m.params.data() + layout.grid_offset);
    for (const NgpLevelReport& r : result.levels)
        if (!r.exact)
            result.notes.push_back("hash-grid level " + std::to_string(r.level) +
                                   " is dense in the snapshot but hashed here: fitted, " +
                                   std::to_string(r.vertices_off) + " of " +
                                   std::to_string(r.vertices_checked) +
                                   " vertices near occupied cells differ (largest difference " +
                                   std::to_string(r.max_error) + ")");
    return result;
}

}  // namespace npt::nerf
