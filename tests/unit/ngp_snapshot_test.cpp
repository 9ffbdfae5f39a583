// instant-ngp snapshot import. No real snapshot ships with the repository, so the tests write one: a small
// MessagePack writer, an fp16 encoder and tiny-cuda-nn's parameter layout are implemented here independently
// of src/nerf/ngp_snapshot.cpp, from the layout documented in docs/formats.md ("instant-ngp snapshots").
// A model of ours with random parameters is written in that layout and imported again; the imported field
// must match the original (bit for bit where both layouts hold the same vertices) and a direct evaluation of
// the snapshot by tiny-cuda-nn's rules everywhere.
#include "nerf/ngp_snapshot.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <variant>
#include <vector>

#include "core/rng.h"
#include "nerf/model_file.h"
#include "test_support.h"

namespace npt::nerf {
namespace {

namespace fs = std::filesystem;

// ---- A minimal MessagePack value and writer (the subset nlohmann::json::to_msgpack produces). ----
struct Mp;
using MpMap = std::vector<std::pair<std::string, Mp>>;
using MpArr = std::vector<Mp>;
using MpBin = std::vector<uint8_t>;
struct Mp {
    std::variant<std::monostate, bool, int64_t, double, std::string, MpBin, MpArr, MpMap> v;
    Mp() = default;
    Mp(bool b) : v(b) {}
    Mp(int i) : v(int64_t(i)) {}
    Mp(int64_t i) : v(i) {}
    Mp(double d) : v(d) {}
    Mp(const char* s) : v(std::string(s)) {}
    Mp(std::string s) : v(std::move(s)) {}
    Mp(MpBin b) : v(std::move(b)) {}
    Mp(MpArr a) : v(std::move(a)) {}
    Mp(MpMap m) : v(std::move(m)) {}
    Mp& operator[](const std::string& key) {  // find or append
        auto& m = std::get<MpMap>(v);
        for (auto& [k, val] : m)
            if (k == key) return val;
        m.emplace_back(key, Mp(MpMap{}));
        return m.back().second;
    }
    void erase(const std::string& key) {
        auto& m = std::get<MpMap>(v);
        for (auto it = m.begin(); it != m.end(); ++it)
            if (it->first == key) {
                m.erase(it);
                return;
            }
    }
};

void put_be(std::vector<uint8_t>& out, uint64_t x, int bytes) {
    for (int i = bytes - 1; i >= 0; --i) out.push_back(uint8_t(x >> (8 * i)));
}

void encode(const Mp& m, std::vector<uint8_t>& out) {
    if (std::holds_alternative<std::monostate>(m.v)) {
        out.push_back(0xc0);
    } else if (auto* b = std::get_if<bool>(&m.v)) {
        out.push_back(*b ? 0xc3 : 0xc2);
    } else if (auto* i = std::get_if<int64_t>(&m.v)) {
        if (*i >= 0 && *i < 128) {
            out.push_back(uint8_t(*i));
        } else if (*i >= 0) {
            out.push_back(0xcf);  // uint64
            put_be(out, uint64_t(*i), 8);
        } else {
            out.push_back(0xd3);  // int64
            put_be(out, uint64_t(*i), 8);
        }
    } else if (auto* d = std::get_if<double>(&m.v)) {
        out.push_back(0xcb);
        uint64_t bits;
        std::memcpy(&bits, d, 8);
        put_be(out, bits, 8);
    } else if (auto* s = std::get_if<std::string>(&m.v)) {
        out.push_back(0xdb);  // str32
        put_be(out, s->size(), 4);
        out.insert(out.end(), s->begin(), s->end());
    } else if (auto* bin = std::get_if<MpBin>(&m.v)) {
        out.push_back(0xc6);  // bin32
        put_be(out, bin->size(), 4);
        out.insert(out.end(), bin->begin(), bin->end());
    } else if (auto* a = std::get_if<MpArr>(&m.v)) {
        out.push_back(0xdd);  // array32
        put_be(out, a->size(), 4);
        for (const Mp& e : *a) encode(e, out);
    } else {
        const auto& mm = std::get<MpMap>(m.v);
        out.push_back(0xdf);  // map32
        put_be(out, mm.size(), 4);
        for (const auto& [k, val] : mm) {
            encode(Mp(k), out);
            encode(val, out);
        }
    }
}

std::vector<uint8_t> gzip(const std::vector<uint8_t>& in) {  // the framing zstr (instant-ngp's .ingp) writes
    z_stream zs{};
    EXPECT_EQ(deflateInit2(&zs, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY), Z_OK);
    std::vector<uint8_t> out(deflateBound(&zs, uLong(in.size())) + 64);
    zs.next_in = const_cast<Bytef*>(in.data());
    zs.avail_in = uInt(in.size());
    zs.next_out = out.data();
    zs.avail_out = uInt(out.size());
    EXPECT_EQ(deflate(&zs, Z_FINISH), Z_STREAM_END);
    out.resize(zs.total_out);
    deflateEnd(&zs);
    return out;
}

// ---- fp16, round to nearest even (no overflow: the tests' values are far below 65504). ----
uint16_t to_half(float f) {
    uint32_t x;
    std::memcpy(&x, &f, 4);
    const uint16_t sign = uint16_t((x >> 16) & 0x8000u);
    const float a = std::fabs(f);
    EXPECT_LT(a, 65504.0f) << f;
    if (a < std::ldexp(1.0f, -14))  // subnormal (or zero): multiples of 2^-24; the scaling is exact
        return uint16_t(sign | uint16_t(std::nearbyint(a * std::ldexp(1.0f, 24))));
    const int exp = int((x >> 23) & 0xff) - 127 + 15;
    const uint32_t mant = x & 0x7fffffu;
    uint32_t h = (uint32_t(exp) << 10) | (mant >> 13);
    const uint32_t rest = mant & 0x1fffu;
    if (rest > 0x1000u || (rest == 0x1000u && (h & 1u))) ++h;  // may carry into the exponent: still right
    return uint16_t(sign | h);
}
float from_half(uint16_t h) {  // finite values only, as to_half produces
    const float sign = (h & 0x8000u) ? -1.0f : 1.0f;
    const int exp = (h >> 10) & 0x1f;
    const int mant = h & 0x3ff;
    if (exp == 0) return sign * std::ldexp(float(mant), -24);
    return sign * std::ldexp(float(mant + 1024), exp - 25);
}
float quantize(float f) { return from_half(to_half(f)); }

MpBin halves(const std::vector<float>& v) {
    MpBin b;
    for (float f : v) {
        const uint16_t h = to_half(f);
        b.push_back(uint8_t(h & 0xff));  // little endian, as the GPU's memory is copied out
        b.push_back(uint8_t(h >> 8));
    }
    return b;
}

// ---- tiny-cuda-nn's layout, written from its documented rules (docs/formats.md). ----
int round_up(int x, int m) { return (x + m - 1) / m * m; }

struct RefLevel {
    float scale;
    uint32_t res, size;
    bool dense;
};
RefLevel ref_level(const HashGridConfig& g, float b, int l) {
    RefLevel r;
    r.scale = std::exp2(float(l) * std::log2(b)) * float(g.base_resolution) - 1.0f;
    r.res = uint32_t(std::ceil(r.scale)) + 1;
    const uint64_t cube = uint64_t(r.res) * r.res * r.res;
    r.size = uint32_t(std::min<uint64_t>((cube + 7) / 8 * 8, g.table_size()));
    r.dense = cube <= g.table_size();
    return r;
}
uint32_t ref_entry(const RefLevel& r, uint32_t x, uint32_t y, uint32_t z) {
    if (r.dense) return (x + y * r.res + z * r.res * r.res) % r.size;
    return (x ^ (y * 2654435761u) ^ (z * 805459861u)) % r.size;
}
uint32_t ref_morton(uint32_t x, uint32_t y, uint32_t z) {
    uint32_t m = 0;
    for (int b = 0; b < 10; ++b)
        m |= (((x >> b) & 1u) << (3 * b)) | (((y >> b) & 1u) << (3 * b + 1)) |
             (((z >> b) & 1u) << (3 * b + 2));
    return m;
}

// A snapshot's network, in tiny-cuda-nn's padded shapes.
struct RefMlp {
    int in_pad, width, hidden, out_pad;
    std::vector<float> w;  // layer after layer, row-major [out][in]
    int layer_in(int l) const { return l == 0 ? in_pad : width; }
    int layer_out(int l) const { return l == hidden ? out_pad : width; }
};

struct RefSnapshot {
    HashGridConfig grid;
    float per_level_scale;
    RefMlp density, color;
    std::vector<std::vector<float>> tables;  // per level, size * F
    std::vector<float> density_grid;         // Morton order per cascade
};

// The snapshot tiny-cuda-nn would hold for `m` (whose parameters must be fp16 values): junk where the
// padding is (never read), each dense level's entries taken from our vertex of the same coordinates.
RefSnapshot snapshot_of(const NerfModel& m, Pcg32& rng) {
    const NerfLayout lay = m.layout();
    RefSnapshot s;
    s.grid = lay.grid;
    s.per_level_scale = lay.grid.per_level_scale;
    auto mlp = [&](const MlpShape& ours, int in_pad, const float* w) {
        RefMlp r{in_pad, ours.width, ours.hidden_layers, round_up(ours.outputs, 16), {}};
        for (int l = 0; l <= r.hidden; ++l)
            for (int o = 0; o < r.layer_out(l); ++o)
                for (int i = 0; i < r.layer_in(l); ++i) {
                    const bool real = o < ours.layer_outputs(l) && i < ours.layer_inputs(l);
                    r.w.push_back(real ? w[ours.layer_offset(l) + size_t(o) * ours.layer_inputs(l) + i]
                                       : quantize(rng.next_float() * 8.0f - 4.0f));
                }
        return r;
    };
    s.density = mlp(lay.density, round_up(lay.grid.output_dims(), 16), m.params.data() + lay.density_offset);
    s.color = mlp(lay.color, lay.color.inputs, m.params.data() + lay.color_offset);
    const int nf = lay.grid.features_per_level;
    for (int l = 0; l < lay.grid.levels; ++l) {
        const RefLevel r = ref_level(lay.grid, s.per_level_scale, l);
        const HashLevel ours = hash_level(lay.grid, l);
        const float* table = m.params.data() + lay.grid_offset + size_t(l) * lay.grid.table_size() * nf;
        std::vector<float> t(size_t(r.size) * nf);
        for (uint32_t e = 0; e < r.size; ++e)
            for (int f = 0; f < nf; ++f) {
                float v;
                if (!r.dense) {
                    v = table[size_t(e) * nf + f];
                } else if (e < r.res * r.res * r.res) {
                    const uint32_t x = e % r.res, y = e / r.res % r.res, z = e / (r.res * r.res);
                    v = table[size_t(hash_grid_index(lay.grid, ours, x, y, z)) * nf + f];
                } else {
                    v = quantize(rng.next_float() - 0.5f);  // alignment padding, read only by aliased corners
                }
                t[size_t(e) * nf + f] = v;
            }
        s.tables.push_back(std::move(t));
    }
    const int res = m.occupancy.resolution();
    const size_t cells = size_t(res) * res * res;
    s.density_grid.resize(m.occupancy.density().size());
    for (size_t c = 0; c < size_t(m.occupancy.cascades()); ++c)
        for (int z = 0; z < res; ++z)
            for (int y = 0; y < res; ++y)
                for (int x = 0; x < res; ++x)
                    s.density_grid[c * cells + ref_morton(x, y, z)] =
                        m.occupancy.density()[c * cells + x + size_t(y) * res + size_t(z) * res * res];
    return s;
}

// The file instant-ngp's Testbed::save_snapshot writes: the network config at the top level, "snapshot"
// holding the parameters (density MLP, colour MLP, grid) and the density grid.
Mp snapshot_file(const RefSnapshot& s) {
    Mp root(MpMap{});
    root["loss"]["otype"] = "Huber";
    root["encoding"] = Mp(MpMap{{"otype", "HashGrid"},
                                {"n_levels", s.grid.levels},
                                {"n_features_per_level", s.grid.features_per_level},
                                {"log2_hashmap_size", s.grid.log2_table_size},
                                {"base_resolution", s.grid.base_resolution},
                                {"per_level_scale", double(s.per_level_scale)}});
    auto net = [](const RefMlp& r) {
        return Mp(MpMap{{"otype", "FullyFusedMLP"},
                        {"activation", "ReLU"},
                        {"output_activation", "None"},
                        {"n_neurons", r.width},
                        {"n_hidden_layers", r.hidden}});
    };
    root["network"] = net(s.density);
    root["rgb_network"] = net(s.color);
    root["dir_encoding"] =
        Mp(MpMap{{"otype", "Composite"},
                 {"nested",
                  Mp(MpArr{Mp(MpMap{{"n_dims_to_encode", 3}, {"otype", "SphericalHarmonics"}, {"degree", 4}}),
                           Mp(MpMap{{"otype", "Identity"}})})}});
    std::vector<float> params = s.density.w;
    params.insert(params.end(), s.color.w.begin(), s.color.w.end());
    for (const auto& t : s.tables) params.insert(params.end(), t.begin(), t.end());
    Mp& snap = root["snapshot"];
    snap["n_params"] = int64_t(params.size());
    snap["params_type"] = "__half";
    snap["params_binary"] = halves(params);
    snap["version"] = 1;
    snap["mode"] = "Nerf";
    snap["density_grid_size"] = 128;
    snap["density_grid_binary"] = halves(s.density_grid);
    snap["nerf"]["aabb_scale"] = 1;
    snap["nerf"]["dataset"] = Mp(MpMap{{"scale", 0.33},
                                       {"offset", Mp(MpArr{0.5, 0.25, 0.75})},
                                       {"aabb_scale", 1},
                                       {"is_hdr", false},
                                       {"from_mitsuba", false},
                                       {"n_extra_learnable_dims", 0}});
    snap["training_step"] = 1234;
    return root;
}

std::vector<uint8_t> bytes_of(const Mp& m) {
    std::vector<uint8_t> out;
    encode(m, out);
    return out;
}

// ---- The snapshot's field evaluated by tiny-cuda-nn's rules (positions in [0,1], padded inputs zero). ----
void ref_query(const RefSnapshot& s, Vec3 p, Vec3 d, float* sigma, Rgb* rgb) {
    const int nf = s.grid.features_per_level;
    std::vector<float> x(size_t(s.density.in_pad), 0.0f);
    for (int l = 0; l < s.grid.levels; ++l) {
        const RefLevel r = ref_level(s.grid, s.per_level_scale, l);
        uint32_t base[3];
        float frac[3];
        for (int a = 0; a < 3; ++a) {
            // tiny-cuda-nn fuses this into one fmaf; nerfpt rounds twice. Half an ulp of a position (1.2e-4
            // of a cell at scale 2048) is a real but tiny difference between the two; rounding as nerfpt does
            // keeps it out of this comparison, which is about the layout.
            volatile float prod = r.scale * p[a];
            const float pos = prod + 0.5f;
            base[a] = uint32_t(std::floor(pos));
            frac[a] = pos - std::floor(pos);
        }
        for (int c = 0; c < 8; ++c) {
            float w = 1.0f;
            uint32_t g[3];
            for (int a = 0; a < 3; ++a) {
                g[a] = base[a] + ((c >> a) & 1);
                w *= (c >> a) & 1 ? frac[a] : 1.0f - frac[a];
            }
            const uint32_t e = ref_entry(r, g[0], g[1], g[2]);
            for (int f = 0; f < nf; ++f) x[size_t(l * nf + f)] += w * s.tables[size_t(l)][size_t(e) * nf + f];
        }
    }
    auto run = [](const RefMlp& m, std::vector<float> in) {
        size_t off = 0;
        for (int l = 0; l <= m.hidden; ++l) {
            std::vector<float> out(size_t(m.layer_out(l)), 0.0f);
            for (int o = 0; o < m.layer_out(l); ++o) {
                for (int i = 0; i < m.layer_in(l); ++i)
                    out[size_t(o)] += m.w[off + size_t(o) * m.layer_in(l) + i] * in[size_t(i)];
                if (l < m.hidden) out[size_t(o)] = std::max(out[size_t(o)], 0.0f);
            }
            off += size_t(m.layer_in(l)) * m.layer_out(l);
            in = std::move(out);
        }
        return in;
    };
    std::vector<float> dens = run(s.density, x);
    *sigma = std::exp(dens[0]);
    // The colour MLP reads [density outputs, SH(2 * ((d + 1) / 2) - 1)].
    std::vector<float> ci(dens);
    float sh[16];
    const Vec3 dd((d.x + 1) * 0.5f * 2 - 1, (d.y + 1) * 0.5f * 2 - 1, (d.z + 1) * 0.5f * 2 - 1);
    sh_encode_deg4(dd, sh);
    ci.insert(ci.end(), sh, sh + 16);
    ci.resize(size_t(s.color.in_pad), 0.0f);
    const std::vector<float> out = run(s.color, ci);
    auto sig = [](float v) { return 1.0f / (1.0f + std::exp(-v)); };
    *rgb = Rgb(sig(out[0]), sig(out[1]), sig(out[2]));
}

// ---- Fixtures. ----

// A small config with dense levels (0, 1: dense in both layouts) and hashed levels (2, 3), 8 grid features
// (padded to 16 by tiny-cuda-nn) and widths of 32.
NerfConfig small_config() {
    NerfConfig c;
    c.encoding.grid = {4, 2, 15, 16, 1.5f};
    c.encoding.finest_resolution = 16.0f * 1.5f * 1.5f * 1.5f;
    c.density_mlp = {1, 32, 16};
    c.color_mlp = {2, 32, 3};
    return c;
}

// Random parameters (grid features of order 1, so that the grid matters) and occupancy, all fp16 values.
NerfModel random_model(const NerfConfig& c, uint64_t seed) {
    NerfModel m = create_model(c, 1.0f, ngp_world_to_model(0.33f, Vec3(0.5f, 0.25f, 0.75f)));
    Pcg32 rng(seed, 7);
    const NerfLayout lay = m.layout();
    for (size_t i = 0; i < lay.total; ++i) {
        const float v = i >= lay.grid_offset ? rng.next_float() * 2.0f - 1.0f : m.params[i];
        m.params[i] = quantize(v);
    }
    std::vector<float> dens(m.occupancy.density().size());
    for (float& d : dens) d = rng.next_float() < 0.7f ? 0.0f : quantize(rng.next_float() * 0.05f);
    m.occupancy.set_density(dens, c.occupancy.threshold);
    return m;
}

fs::path write(const fs::path& path, const std::vector<uint8_t>& b) {
    std::ofstream f(path, std::ios::binary);
    f.write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
    return path;
}

// The highest coordinate below which no level that tiny-cuda-nn keeps dense reads an aliased corner there:
// a corner at index resolution - 1 + 1 is used once p * scale + 0.5 >= ceil(scale).
float alias_free_limit(const RefSnapshot& s) {
    float lim = 1.0f;
    for (int l = 0; l < s.grid.levels; ++l) {
        const RefLevel r = ref_level(s.grid, s.per_level_scale, l);
        if (r.dense) lim = std::min(lim, (std::ceil(r.scale) - 0.5f) / r.scale);
    }
    return lim;
}

Vec3 random_dir(Pcg32& rng) {
    for (;;) {
        const Vec3 v(rng.next_float() * 2 - 1, rng.next_float() * 2 - 1, rng.next_float() * 2 - 1);
        const float l = std::sqrt(dot(v, v));
        if (l > 0.1f && l <= 1.0f) return v / l;
    }
}

void expect_same_field(const NerfModel& original, const NerfModel& imported, const RefSnapshot& snap) {
    const NerfFieldView a = original.field(), b = imported.field();
    Pcg32 rng(99, 1);
    const float lim = alias_free_limit(snap);
    ASSERT_GT(lim, 0.9f);
    int interior = 0;
    for (int i = 0; i < 4000; ++i) {
        // Corners and faces of the cube too, where tiny-cuda-nn's dense levels alias.
        Vec3 p(rng.next_float(), rng.next_float(), rng.next_float());
        if (i % 10 == 0) p[i / 10 % 3] = (i / 30) % 2 ? 1.0f : 0.0f;
        const Vec3 d = random_dir(rng);
        float sa, sb, sr;
        Rgb ca, cb, cr;
        b.query(p, d, &sb, &cb);
        ref_query(snap, p, d, &sr, &cr);
        // Against tiny-cuda-nn's rules: the same sums in another order (fma, padded zeros), so float
        // rounding only: 1e-5 relative on sigma = exp(raw) (raw of order 1, a few ulps of 1e-7 each),
        // 1e-6 on the colour.
        EXPECT_NEAR(sb, sr, 1e-5f * sr) << "p " << p.x << " " << p.y << " " << p.z;
        EXPECT_NEAR(cb.x, cr.x, 1e-6f);
        EXPECT_NEAR(cb.y, cr.y, 1e-6f);
        EXPECT_NEAR(cb.z, cr.z, 1e-6f);
        if (p.x < lim && p.y < lim && p.z < lim) {
            // Same parameters, same vertices, same code: bit for bit.
            ++interior;
            a.query(p, d, &sa, &ca);
            EXPECT_EQ(sa, sb);
            EXPECT_EQ(ca.x, cb.x);
            EXPECT_EQ(ca.y, cb.y);
            EXPECT_EQ(ca.z, cb.z);
        }
    }
    EXPECT_GT(interior, 2000);
}

TEST(NgpSnapshot, ImportsTheFieldOfAModelWrittenInInstantNgpLayout) {
    const NerfModel original = random_model(small_config(), 5);
    Pcg32 rng(3, 3);
    const RefSnapshot snap = snapshot_of(original, rng);
    const fs::path path = write(test::temp_dir() / "model.msgpack", bytes_of(snapshot_file(snap)));
    const NgpImport imp = import_ngp_snapshot(path);
    const NerfModel& m = imp.model;
    EXPECT_EQ(imp.training_step, 1234u);
    ASSERT_EQ(imp.levels.size(), 4u);
    for (const auto& l : imp.levels) EXPECT_TRUE(l.exact) << l.level;
    EXPECT_TRUE(imp.levels[0].dense_in_snapshot && imp.levels[0].dense_here);
    EXPECT_TRUE(!imp.levels[3].dense_in_snapshot && !imp.levels[3].dense_here);
    EXPECT_EQ(m.layout().grid.per_level_scale, original.layout().grid.per_level_scale);
    EXPECT_EQ(m.layout().total, original.layout().total);
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c)
            EXPECT_FLOAT_EQ(m.world_to_model.m[r][c], original.world_to_model.m[r][c]);
    expect_same_field(original, m, snap);
    // The occupancy grid: Morton order back to x-fastest, the same fp16 values.
    EXPECT_EQ(m.occupancy.density(), original.occupancy.density());
    EXPECT_EQ(m.occupancy.occupied_fraction(), original.occupancy.occupied_fraction());
}

TEST(NgpSnapshot, CompressedIngpAndModelFile) {
    const NerfModel original = random_model(small_config(), 6);
    Pcg32 rng(4, 3);
    const RefSnapshot snap = snapshot_of(original, rng);
    const fs::path dir = test::temp_dir();
    const fs::path path = write(dir / "model.ingp", gzip(bytes_of(snapshot_file(snap))));
    const NgpImport imp = import_ngp_snapshot(path);
    save_model(dir / "model.npt", imp.model, false);
    const NerfModel loaded = load_model(dir / "model.npt");
    expect_same_field(original, loaded, snap);
}

TEST(NgpSnapshot, DefaultsDerivedAsTheTestbedDoes) {
    // Without per_level_scale the testbed derives it from 2048 * aabb_scale; that is our default
    // finest_resolution, so the import must land on the same float.
    NerfConfig c = small_config();
    c.encoding.finest_resolution = 2048.0f;
    const NerfModel original = random_model(c, 8);
    Pcg32 rng(5, 3);
    const RefSnapshot snap = snapshot_of(original, rng);
    Mp file = snapshot_file(snap);
    file["encoding"].erase("per_level_scale");
    const NgpImport imp = import_ngp_snapshot(bytes_of(file), "s.msgpack");
    EXPECT_EQ(imp.model.config.encoding.finest_resolution, 2048.0f);
    EXPECT_EQ(imp.model.layout().grid.per_level_scale, original.layout().grid.per_level_scale);
    expect_same_field(original, imp.model, snap);
}

TEST(NgpSnapshot, DensityGridMortonOrderAndUntrainedCells) {
    // Two cascades, 4^3 cells: each cell holds its own x-fastest index, stored at its Morton index.
    const int r = 4, cells = r * r * r;
    std::vector<float> ngp(2 * cells);
    for (int c = 0; c < 2; ++c)
        for (int z = 0; z < r; ++z)
            for (int y = 0; y < r; ++y)
                for (int x = 0; x < r; ++x)
                    ngp[c * cells + ref_morton(x, y, z)] = float(c * cells + x + y * r + z * r * r);
    ngp[ref_morton(1, 2, 3)] = -1.0f;  // never trained
    const std::vector<float> ours = ngp_density_grid_to_occupancy(ngp, 2, r, "s");
    for (int i = 0; i < 2 * cells; ++i) EXPECT_EQ(ours[i], i == 1 + 2 * r + 3 * r * r ? 0.0f : float(i)) << i;
    EXPECT_EQ(ngp_morton3(1, 0, 0), 1u);
    EXPECT_EQ(ngp_morton3(0, 1, 0), 2u);
    EXPECT_EQ(ngp_morton3(0, 0, 1), 4u);
    EXPECT_EQ(ngp_morton3(127, 127, 127), 128u * 128u * 128u - 1u);
    test::expect_error_message([&] { ngp_density_grid_to_occupancy(ngp, 3, r, "s.ingp"); },
                               {"s.ingp", "density_grid_binary"});
}

TEST(NgpSnapshot, HalfFloats) {
    EXPECT_EQ(ngp_half_to_float(0x3c00), 1.0f);
    EXPECT_EQ(ngp_half_to_float(0xc000), -2.0f);
    EXPECT_EQ(ngp_half_to_float(0x7bff), 65504.0f);
    EXPECT_EQ(ngp_half_to_float(0x0001), std::ldexp(1.0f, -24));  // smallest subnormal
    EXPECT_EQ(ngp_half_to_float(0x03ff), std::ldexp(1023.0f, -24));
    EXPECT_TRUE(std::isinf(ngp_half_to_float(0x7c00)));
    EXPECT_TRUE(std::isnan(ngp_half_to_float(0x7e00)));
    for (float f : {0.1f, -3.75f, 1234.5f, 1e-3f}) EXPECT_EQ(ngp_half_to_float(to_half(f)), quantize(f));
}

// A level tiny-cuda-nn keeps dense (16^3 entries fill 2^12 exactly) but we hash (17^3 > 2^12).
RefSnapshot mismatched_snapshot(bool constant_level0, NerfModel& original) {
    NerfConfig c = small_config();
    c.encoding.grid.log2_table_size = 12;
    original = random_model(c, 9);
    Pcg32 rng(6, 3);
    RefSnapshot snap = snapshot_of(original, rng);
    EXPECT_TRUE(ref_level(snap.grid, snap.per_level_scale, 0).dense);
    EXPECT_FALSE(hash_level(original.layout().grid, 0).dense);
    for (size_t i = 0; i < snap.tables[0].size(); ++i)
        snap.tables[0][i] = constant_level0 ? (i % 2 ? 0.25f : -0.5f) : quantize(rng.next_float() - 0.5f);
    return snap;
}

TEST(NgpSnapshot, LevelDenseInTheSnapshotButHashedHereIsFittedAndReported) {
    NerfModel original;
    {
        // Constant features: every shared entry agrees, so the fit is exact and the field matches.
        const RefSnapshot snap = mismatched_snapshot(true, original);
        const NgpImport imp = import_ngp_snapshot(bytes_of(snapshot_file(snap)), "s.msgpack");
        ASSERT_FALSE(imp.levels[0].exact);
        EXPECT_EQ(imp.levels[0].vertices_off, 0u);
        EXPECT_GT(imp.levels[0].vertices_checked, 0u);
        const NerfFieldView b = imp.model.field();
        Pcg32 rng(1, 1);
        for (int i = 0; i < 500; ++i) {
            const Vec3 p(rng.next_float(), rng.next_float(), rng.next_float()), d = random_dir(rng);
            float sb, sr;
            Rgb cb, cr;
            b.query(p, d, &sb, &cb);
            ref_query(snap, p, d, &sr, &cr);
            EXPECT_NEAR(sb, sr, 1e-5f * sr);
            EXPECT_NEAR(cb.y, cr.y, 1e-6f);
        }
    }
    {
        // Random features: collisions cannot all be kept; the report says so and a note is written.
        const RefSnapshot snap = mismatched_snapshot(false, original);
        const NgpImport imp = import_ngp_snapshot(bytes_of(snapshot_file(snap)), "s.msgpack");
        ASSERT_FALSE(imp.levels[0].exact);
        EXPECT_GT(imp.levels[0].vertices_off, 0u);
        EXPECT_LE(imp.levels[0].max_error, 1.0f);  // features in [-0.5, 0.5]: a mean is never further off
        bool noted = false;
        for (const auto& n : imp.notes) noted = noted || n.find("level 0") != std::string::npos;
        EXPECT_TRUE(noted);
        for (int l = 1; l < 4; ++l) EXPECT_TRUE(imp.levels[size_t(l)].exact);
    }
}

// ---- Bad input: one-line errors naming the file and the field. ----

Mp good_file() {
    static const RefSnapshot snap = [] {
        Pcg32 rng(1, 2);
        return snapshot_of(random_model(small_config(), 1), rng);
    }();
    return snapshot_file(snap);
}

void expect_import_error(const std::vector<uint8_t>& bytes, std::initializer_list<std::string> parts) {
    test::expect_error_message([&] { import_ngp_snapshot(bytes, "bad.msgpack"); }, parts);
}

TEST(NgpSnapshot, BadFiles) {
    const fs::path dir = test::temp_dir();
    test::expect_error_message([&] { import_ngp_snapshot(dir / "missing.ingp"); },
                               {"missing.ingp", "no such file"});
    test::expect_error_message([&] { import_ngp_snapshot(write(dir / "empty.msgpack", {})); },
                               {"empty.msgpack", "empty"});
    const std::vector<uint8_t> good = bytes_of(good_file());
    EXPECT_NO_THROW(import_ngp_snapshot(good, "good.msgpack"));
    expect_import_error(std::vector<uint8_t>(good.begin(), good.begin() + long(good.size() / 2)),
                        {"bad.msgpack", "not a MessagePack snapshot"});
    const std::vector<uint8_t> gz = gzip(good);
    expect_import_error(std::vector<uint8_t>(gz.begin(), gz.begin() + long(gz.size() / 2)),
                        {"bad.msgpack", "truncated"});
    const std::string text = "{\"snapshot\": 1}";
    expect_import_error(std::vector<uint8_t>(text.begin(), text.end()), {"bad.msgpack", "not a MessagePack"});
    expect_import_error(bytes_of(Mp(MpArr{1, 2})), {"bad.msgpack", "not a map"});
    // A blob claiming 4 GiB in a file of 9 bytes: an error, not an allocation.
    expect_import_error({0x81, 0xa1, 'a', 0xc6, 0xff, 0xff, 0xff, 0xff, 0x00},
                        {"bad.msgpack", "not a MessagePack snapshot"});
}

// nlohmann's MessagePack reader recurses once per level: 200 000 nested arrays overflowed the stack.
TEST(NgpSnapshot, DeeplyNestedIsAnErrorNotACrash) {
    std::vector<uint8_t> deep(3 + 200000 + 1, 0x91);  // {"a": [[[...[nil]...]]]}
    deep[0] = 0x81;
    deep[1] = 0xa1;
    deep[2] = 'a';
    deep.back() = 0xc0;
    expect_import_error(deep, {"bad.msgpack", "nested deeper than 256 levels"});
    expect_import_error(gzip(deep), {"bad.msgpack", "nested deeper"});
}

TEST(NgpSnapshot, MissingKeys) {
    for (const char* key : {"snapshot", "encoding", "network", "rgb_network", "dir_encoding"}) {
        Mp f = good_file();
        f.erase(key);
        expect_import_error(bytes_of(f), {"bad.msgpack", std::string("'") + key + "' is missing"});
    }
    for (const char* key : {"params_binary", "nerf", "density_grid_binary"}) {
        Mp f = good_file();
        f["snapshot"].erase(key);
        expect_import_error(bytes_of(f), {"bad.msgpack", std::string("'snapshot.") + key + "' is missing"});
    }
}

TEST(NgpSnapshot, UnsupportedConfigs) {
    struct Case {
        std::function<void(Mp&)> edit;
        std::string field;
    };
    const std::vector<Case> cases = {
        {[](Mp& f) { f["encoding"]["otype"] = "Frequency"; }, "encoding.otype"},
        {[](Mp& f) { f["encoding"]["type"] = "Dense"; }, "encoding.type"},
        {[](Mp& f) { f["encoding"]["interpolation"] = "Smoothstep"; }, "encoding.interpolation"},
        {[](Mp& f) { f["encoding"]["n_features_per_level"] = 3; }, "encoding.n_features_per_level"},
        {[](Mp& f) { f["network"]["activation"] = "Sigmoid"; }, "network.activation"},
        {[](Mp& f) { f["network"]["output_activation"] = "Exponential"; }, "network.output_activation"},
        {[](Mp& f) { f["rgb_network"]["n_neurons"] = 256; }, "rgb_network.n_neurons"},
        {[](Mp& f) { f["network"]["otype"] = "SIREN"; }, "network.otype"},
        {[](Mp& f) {
             f["dir_encoding"] = Mp(MpMap{{"otype", "Frequency"}});
         },
         "dir_encoding.otype"},
        {[](Mp& f) {
             f["dir_encoding"] = Mp(MpMap{{"otype", "SphericalHarmonics"}, {"degree", 3}});
         },
         "dir_encoding.degree"},
        {[](Mp& f) { f["snapshot"]["nerf"]["dataset"]["is_hdr"] = true; }, "snapshot.nerf.dataset.is_hdr"},
        {[](Mp& f) { f["snapshot"]["mode"] = "Sdf"; }, "snapshot.mode"},
        {[](Mp& f) { f["snapshot"]["params_type"] = "double"; }, "snapshot.params_type"},
        {[](Mp& f) { f["snapshot"]["n_params"] = 12; }, "snapshot.n_params"},
        {[](Mp& f) { f["encoding"]["n_levels"] = "many"; }, "encoding.n_levels"},
    };
    for (const Case& c : cases) {
        Mp f = good_file();
        c.edit(f);
        expect_import_error(bytes_of(f), {"bad.msgpack", "'" + c.field + "'"});
    }
}

TEST(NgpSnapshot, WrongParameterCount) {
    Mp f = good_file();
    auto& bin = std::get<MpBin>(f["snapshot"]["params_binary"].v);
    bin.resize(bin.size() - 2);  // one fp16 value short
    f["snapshot"].erase("n_params");
    expect_import_error(bytes_of(f),
                        {"bad.msgpack", "'snapshot.params_binary'", "parameters; the config needs"});
    Mp g = good_file();
    std::get<MpBin>(g["snapshot"]["density_grid_binary"].v).resize(1000);
    expect_import_error(bytes_of(g), {"bad.msgpack", "'snapshot.density_grid_binary'"});
}

}  // namespace
}  // namespace npt::nerf
