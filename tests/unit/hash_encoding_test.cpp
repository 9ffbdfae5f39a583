// Hash-grid encoding (nerf/hash_encoding.h): backward against central differences of the forward, forward
// against an independent float64 reference, exact reproduction of linear functions on dense levels,
// dense/hash selection by table size, and in-range corners on the cube's faces, edges and corners.
#include "nerf/hash_encoding.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

namespace npt::nerf {
namespace {

constexpr double k_u = 1.0 / (1 << 24);  // unit roundoff of float

// Small enough to be fast, with levels 0-2 dense (5, 8, 12 vertices per axis; 12^3 <= 4096) and 3-7 hashed.
HashGridConfig small_config() {
    HashGridConfig cfg;
    cfg.levels = 8;
    cfg.features_per_level = 2;
    cfg.log2_table_size = 12;
    cfg.base_resolution = 4;
    cfg.per_level_scale = 1.6f;
    return cfg;
}

std::vector<float> random_params(const HashGridConfig& cfg, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<float> params(cfg.param_count());
    for (float& v : params) v = u(rng);
    return params;
}

std::vector<Vec3> random_points(int n, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<Vec3> pts;
    for (int i = 0; i < n; ++i) pts.push_back(Vec3(u(rng), u(rng), u(rng)));
    return pts;
}

// L(params) = sum over points and outputs of w_k * out_k, summed in double so that only the float forward
// itself contributes rounding.
double weighted_loss(const HashGridConfig& cfg, const std::vector<float>& params,
                     const std::vector<Vec3>& pts, const std::vector<float>& w) {
    std::vector<float> out(cfg.output_dims());
    double loss = 0.0;
    for (Vec3 p : pts) {
        hash_encode(cfg, params.data(), p, out.data());
        for (int k = 0; k < cfg.output_dims(); ++k) loss += double(w[k]) * out[k];
    }
    return loss;
}

TEST(HashEncoding, BackwardMatchesCentralDifferences) {
    const HashGridConfig cfg = small_config();
    const int nf = cfg.features_per_level;
    std::mt19937 rng(7);
    std::vector<float> params = random_params(cfg, rng);
    const std::vector<Vec3> pts = random_points(48, rng);
    std::vector<float> w(cfg.output_dims());
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (float& v : w) v = u(rng);

    std::vector<float> grad(params.size(), 0.0f);
    for (Vec3 p : pts) hash_encode_backward(cfg, p, w.data(), grad.data());

    // S_j = sum of |w_k| over every (point, output) that reads parameter j: it bounds both the rounding of
    // the float accumulation in the backward pass and that of the outputs the difference quotient depends on.
    std::vector<double> s(params.size(), 0.0);
    std::vector<int> touches(params.size(), 0);
    for (Vec3 p : pts) {
        for (int l = 0; l < cfg.levels; ++l) {
            HashCorner c[8];
            hash_level_corners(cfg, l, p, c);
            for (int i = 0; i < 8; ++i)
                for (int f = 0; f < nf; ++f) {
                    const size_t j = size_t(c[i].index) * nf + f;
                    s[j] += std::fabs(w[l * nf + f]);
                    ++touches[j];
                }
        }
    }
    // A few hundred parameters: all touched by several points (the coarse dense levels), then touched once,
    // then never touched (gradient exactly 0).
    std::vector<size_t> chosen_multi, chosen_single, chosen_none;
    for (size_t j = 0; j < params.size(); ++j) {
        if (touches[j] >= 2 && chosen_multi.size() < 200) chosen_multi.push_back(j);
        if (touches[j] == 1 && chosen_single.size() < 100) chosen_single.push_back(j);
        if (touches[j] == 0 && chosen_none.size() < 50 && j % 97 == 0) chosen_none.push_back(j);
    }
    ASSERT_EQ(chosen_multi.size(), 200u);
    ASSERT_EQ(chosen_single.size(), 100u);
    std::vector<size_t> chosen = chosen_multi;
    chosen.insert(chosen.end(), chosen_single.begin(), chosen_single.end());
    chosen.insert(chosen.end(), chosen_none.begin(), chosen_none.end());

    // The encoding is linear in the parameters, so a central difference has no truncation error and the step
    // can be large (h = 1): the error is only float rounding of the outputs, at most ~9u per output with
    // |params| <= 2, twice (L+ and L-), divided by 2h; the backward's own accumulation adds <= touches * u.
    // 64 u S_j covers both with margin.
    const float h = 1.0f;
    int nonzero = 0;
    for (size_t j : chosen) {
        const float saved = params[j];
        params[j] = saved + h;
        const double lp = weighted_loss(cfg, params, pts, w);
        params[j] = saved - h;
        const double lm = weighted_loss(cfg, params, pts, w);
        params[j] = saved;
        const double fd = (lp - lm) / (2.0 * h);
        const double tol = 64.0 * k_u * (s[j] + 1e-30);
        EXPECT_NEAR(grad[j], fd, tol) << "param " << j << " touched " << touches[j] << " times";
        if (touches[j] == 0) {
            EXPECT_EQ(grad[j], 0.0f);
        }
        if (grad[j] != 0.0f) ++nonzero;
    }
    EXPECT_GT(nonzero, 250);  // not a vacuous comparison of zeros
}

// Float64 reference of the documented convention, written from the header comment, not from its code.
void reference_encode(const HashGridConfig& cfg, const std::vector<float>& params, Vec3 p, double* out) {
    const uint64_t t = uint64_t(1) << cfg.log2_table_size;
    const int nf = cfg.features_per_level;
    for (int l = 0; l < cfg.levels; ++l) {
        const double scale = std::pow(double(cfg.per_level_scale), l) * cfg.base_resolution - 1.0;
        const uint64_t v = uint64_t(std::ceil(scale)) + 2;
        const bool dense = v * v * v <= t;
        double pos[3], fr[3];
        int64_t g0[3];
        for (int a = 0; a < 3; ++a) {
            pos[a] = double(p[a]) * scale + 0.5;
            g0[a] = int64_t(std::floor(pos[a]));
            fr[a] = pos[a] - double(g0[a]);
        }
        for (int f = 0; f < nf; ++f) out[l * nf + f] = 0.0;
        for (int dz = 0; dz < 2; ++dz)
            for (int dy = 0; dy < 2; ++dy)
                for (int dx = 0; dx < 2; ++dx) {
                    const uint64_t x = g0[0] + dx, y = g0[1] + dy, z = g0[2] + dz;
                    uint64_t idx;
                    if (dense) {
                        idx = (z * v + y) * v + x;
                    } else {
                        const uint64_t hsh = (x * 1ull) ^ ((y * 2654435761ull) & 0xffffffffull) ^
                                             ((z * 805459861ull) & 0xffffffffull);
                        idx = (hsh & 0xffffffffull) % t;
                    }
                    const double wgt =
                        (dx ? fr[0] : 1 - fr[0]) * (dy ? fr[1] : 1 - fr[1]) * (dz ? fr[2] : 1 - fr[2]);
                    for (int f = 0; f < nf; ++f) out[l * nf + f] += wgt * params[(l * t + idx) * nf + f];
                }
    }
}

TEST(HashEncoding, ForwardMatchesFloat64Reference) {
    const HashGridConfig cfg = small_config();
    std::mt19937 rng(11);
    const std::vector<float> params = random_params(cfg, rng);
    std::vector<float> out(cfg.output_dims());
    std::vector<double> ref(cfg.output_dims());
    for (Vec3 p : random_points(200, rng)) {
        hash_encode(cfg, params.data(), p, out.data());
        reference_encode(cfg, params, p, ref.data());
        for (int l = 0; l < cfg.levels; ++l) {
            // The float grid position differs from the float64 one by the rounding of scale (exp2f/log2f,
            // a few ulp) and of p * scale + 0.5: <= 16 u (scale + 1) per axis. Trilinear interpolation of
            // values in [-1, 1] has slope <= 2 per axis, so 3 axes give 6 * that; plus ~20 u for the float
            // sum.
            const double scale = hash_level(cfg, l).scale;
            const double tol = 6.0 * 16.0 * k_u * (scale + 1.0) + 20.0 * k_u;
            for (int f = 0; f < cfg.features_per_level; ++f) {
                const int k = l * cfg.features_per_level + f;
                EXPECT_NEAR(out[k], ref[k], tol) << "level " << l;
            }
        }
    }
}

TEST(HashEncoding, DenseLevelReproducesLinearFunction) {
    const HashGridConfig cfg = small_config();
    const int level = 2, nf = cfg.features_per_level;
    const HashLevel lv = hash_level(cfg, level);
    ASSERT_TRUE(lv.dense);
    std::vector<float> params(cfg.param_count(), 0.0f);
    // Feature f at vertex (x, y, z) = a_f + b_f . (x, y, z): trilinear interpolation of it is exact.
    const double a[2] = {0.25, -0.5};
    const double b[2][3] = {{0.5, -0.25, 0.125}, {-0.0625, 0.375, 1.0}};
    const uint32_t v = lv.vertices;
    for (uint32_t z = 0; z < v; ++z)
        for (uint32_t y = 0; y < v; ++y)
            for (uint32_t x = 0; x < v; ++x) {
                const size_t e = size_t(level) * cfg.table_size() + hash_grid_index(cfg, lv, x, y, z);
                for (int f = 0; f < nf; ++f)
                    params[e * nf + f] = float(a[f] + b[f][0] * x + b[f][1] * y + b[f][2] * z);
            }
    std::mt19937 rng(3);
    std::vector<float> out(cfg.output_dims());
    for (Vec3 p : random_points(500, rng)) {
        hash_encode(cfg, params.data(), p, out.data());
        for (int f = 0; f < nf; ++f) {
            double expect = a[f], mag = std::fabs(a[f]);
            for (int ax = 0; ax < 3; ++ax) {
                expect += b[f][ax] * (double(p[ax]) * lv.scale + 0.5);
                mag += std::fabs(b[f][ax]) * v;
            }
            // Rounding of the grid position (u (scale + 1) per axis, times |b|) and of the 8-term weighted
            // sum of values <= mag: 16 u mag bounds both.
            EXPECT_NEAR(out[level * nf + f], expect, 16.0 * k_u * mag) << p.x << " " << p.y << " " << p.z;
        }
    }
}

TEST(HashEncoding, DenseOrHashedFollowsTableSize) {
    HashGridConfig cfg;  // instant-ngp defaults: 16 levels, T = 2^19, base 16
    cfg.per_level_scale = per_level_scale_for(16, 2048.0f, 16);
    EXPECT_NEAR(cfg.per_level_scale, std::exp(std::log(128.0) / 15.0), 1e-6);
    int dense_levels = 0;
    for (int l = 0; l < cfg.levels; ++l) {
        const HashLevel lv = hash_level(cfg, l);
        const uint64_t v = lv.vertices;
        EXPECT_EQ(lv.dense, v * v * v <= (uint64_t(1) << 19)) << "level " << l;
        dense_levels += lv.dense;
    }
    // ceil(16 b^l - 1) + 2 vertices: 17, 24, 32, 44, 60 (216000 <= 524288), 82 (551368 > 524288), ...
    EXPECT_EQ(dense_levels, 5);
    EXPECT_TRUE(hash_level(cfg, 4).dense);
    EXPECT_FALSE(hash_level(cfg, 5).dense);
    EXPECT_NEAR(hash_level(cfg, 15).scale, 2047.0f, 2047.0f * 1e-5f);

    // Shrinking the table turns level 0 (17^3 = 4913 entries) from dense into hashed.
    cfg.log2_table_size = 13;
    EXPECT_TRUE(hash_level(cfg, 0).dense);
    cfg.log2_table_size = 12;
    EXPECT_FALSE(hash_level(cfg, 0).dense);

    // The boundary: base 15 gives scale 14, 16 vertices, 16^3 = 4096 = T entries, which still fit densely.
    HashGridConfig edge = small_config();
    edge.base_resolution = 15;
    EXPECT_EQ(hash_level(edge, 0).vertices, 16u);
    EXPECT_TRUE(hash_level(edge, 0).dense);
    edge.log2_table_size = 11;
    EXPECT_FALSE(hash_level(edge, 0).dense);

    // Dense indexing is a bijection onto [0, V^3); hashed indexing is the documented hash.
    HashGridConfig small = small_config();
    const HashLevel lv0 = hash_level(small, 0);
    ASSERT_TRUE(lv0.dense);
    std::set<uint32_t> seen;
    for (uint32_t z = 0; z < lv0.vertices; ++z)
        for (uint32_t y = 0; y < lv0.vertices; ++y)
            for (uint32_t x = 0; x < lv0.vertices; ++x) {
                const uint32_t i = hash_grid_index(small, lv0, x, y, z);
                EXPECT_LT(i, lv0.vertices * lv0.vertices * lv0.vertices);
                seen.insert(i);
            }
    EXPECT_EQ(seen.size(), size_t(lv0.vertices) * lv0.vertices * lv0.vertices);
    const HashLevel lv5 = hash_level(small, 5);
    ASSERT_FALSE(lv5.dense);
    const uint64_t hsh =
        (3ull ^ ((5ull * 2654435761ull) & 0xffffffffull) ^ ((7ull * 805459861ull) & 0xffffffffull));
    EXPECT_EQ(hash_grid_index(small, lv5, 3, 5, 7), uint32_t(hsh % 4096));
}

void expect_corners_in_range(const HashGridConfig& cfg, Vec3 p) {
    for (int l = 0; l < cfg.levels; ++l) {
        const HashLevel lv = hash_level(cfg, l);
        const uint64_t limit =
            lv.dense ? uint64_t(lv.vertices) * lv.vertices * lv.vertices : uint64_t(cfg.table_size());
        HashCorner c[8];
        hash_level_corners(cfg, l, p, c);
        double wsum = 0.0;
        for (int i = 0; i < 8; ++i) {
            const uint64_t first = uint64_t(l) * cfg.table_size();
            ASSERT_GE(c[i].index, first) << "level " << l << " p " << p.x << " " << p.y << " " << p.z;
            ASSERT_LT(c[i].index - first, limit) << "level " << l << " p " << p.x << " " << p.y << " " << p.z;
            ASSERT_GE(c[i].weight, 0.0f);
            wsum += c[i].weight;
        }
        EXPECT_NEAR(wsum, 1.0, 8 * k_u);
    }
}

TEST(HashEncoding, FacesAndCornersStayInRange) {
    HashGridConfig big;
    big.per_level_scale = per_level_scale_for(16, 4096.0f, 16);
    HashGridConfig odd = small_config();
    odd.per_level_scale = 2.0f;  // integer scales (3, 7, 15, 31, ...): p = 1 lands exactly on a vertex
    const float below1 = std::nextafter(1.0f, 0.0f);
    // Outside values are clamped to the cube, so they are included too.
    const float vals[] = {0.0f, 1e-7f, 0.5f, below1, 1.0f, -0.25f, 1.5f};
    for (const HashGridConfig& cfg : {small_config(), odd, big})
        for (float x : vals)
            for (float y : vals)
                for (float z : vals) expect_corners_in_range(cfg, Vec3(x, y, z));
    // And the forward pass reads only the parameter array (ASan would flag it otherwise).
    const HashGridConfig cfg = small_config();
    std::vector<float> params(cfg.param_count(), 1.0f), out(cfg.output_dims());
    hash_encode(cfg, params.data(), Vec3(1.0f, 1.0f, 1.0f), out.data());
    for (float o : out) EXPECT_NEAR(o, 1.0f, 8 * k_u);
}

}  // namespace
}  // namespace npt::nerf
