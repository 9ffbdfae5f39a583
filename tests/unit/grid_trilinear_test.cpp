// sample_trilinear (media/grid.h) against a float64 evaluation of the same definition: voxel (i, j, k) at
// index point (i, j, k), trilinear weights, voxels outside the grid counting as 0.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "media/grid.h"

namespace npt::media {
namespace {

struct RandomGrid {
    int nx = 5, ny = 4, nz = 3;
    std::vector<float> density;
    std::vector<Vec3> color;
    explicit RandomGrid(std::mt19937& rng) {
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        for (int n = 0; n < nx * ny * nz; ++n) {
            density.push_back(u(rng));
            color.push_back(Vec3(u(rng), u(rng), u(rng)));
        }
    }
    GridView view() const { return GridView{nx, ny, nz, density.data(), color.data(), Affine3{}}; }
    // Float64 reference of the same definition.
    void reference(Vec3 x, double& d, double c[3]) const {
        d = c[0] = c[1] = c[2] = 0.0;
        const double fx = std::floor(double(x.x)), fy = std::floor(double(x.y)), fz = std::floor(double(x.z));
        const double t[3] = {x.x - fx, x.y - fy, x.z - fz};
        for (int corner = 0; corner < 8; ++corner) {
            const int o[3] = {corner & 1, (corner >> 1) & 1, (corner >> 2) & 1};
            const int i = int(fx) + o[0], j = int(fy) + o[1], k = int(fz) + o[2];
            if (i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz) continue;
            double w = 1.0;
            for (int a = 0; a < 3; ++a) w *= o[a] ? t[a] : 1.0 - t[a];
            const size_t idx = (size_t(k) * ny + j) * nx + i;
            d += w * density[idx];
            c[0] += w * color[idx].x;
            c[1] += w * color[idx].y;
            c[2] += w * color[idx].z;
        }
    }
};

TEST(Trilinear, MatchesFloat64ReferenceInsideNearAndOutsideTheBorder) {
    std::mt19937 rng(7);
    RandomGrid g(rng);
    // Points over [-1.5, n + 0.5] per axis: inside, in the half-weighted border cells and fully outside.
    std::uniform_real_distribution<float> ux(-1.5f, g.nx + 0.5f), uy(-1.5f, g.ny + 0.5f),
        uz(-1.5f, g.nz + 0.5f);
    // Float rounding: x - floor(x) is exact, each of (1 - t), the 2 weight products and the 8 multiply-adds
    // rounds once (relative 2^-24), so |error| <= ~12 * 2^-24 * sum(w * |v|) <= 12 * 2^-24 for values in [0,
    // 1] (sum of weights <= 1). We allow 16 * 2^-24 ~ 9.5e-7.
    const double tol = 16.0 * std::ldexp(1.0, -24);
    int outside = 0;
    for (int n = 0; n < 20000; ++n) {
        const Vec3 x(ux(rng), uy(rng), uz(rng));
        double d, c[3];
        g.reference(x, d, c);
        const FieldSample s = sample_trilinear(g.view(), x);
        ASSERT_NEAR(s.density, d, tol) << x.x << " " << x.y << " " << x.z;
        EXPECT_NEAR(s.color.x, c[0], tol);
        EXPECT_NEAR(s.color.y, c[1], tol);
        EXPECT_NEAR(s.color.z, c[2], tol);
        outside += d == 0.0;
    }
    EXPECT_GT(outside, 1000);  // the sample covered the outside, where both must be exactly 0
}

TEST(Trilinear, VoxelValueSitsAtItsIntegerIndexAndNaNGivesZero) {
    std::mt19937 rng(3);
    RandomGrid g(rng);
    const GridView v = g.view();
    for (int k = 0; k < g.nz; ++k)
        for (int j = 0; j < g.ny; ++j)
            for (int i = 0; i < g.nx; ++i)
                EXPECT_EQ(sample_trilinear(v, Vec3(float(i), float(j), float(k))).density,
                          g.density[v.index(i, j, k)]);
    EXPECT_EQ(sample_trilinear(v, Vec3(NAN, 1.0f, 1.0f)).density, 0.0f);
    EXPECT_EQ(sample_trilinear(v, Vec3(-1.0f, 1.0f, 1.0f)).density, 0.0f);
    EXPECT_EQ(sample_trilinear(v, Vec3(float(g.nx), 1.0f, 1.0f)).density, 0.0f);
}

}  // namespace
}  // namespace npt::media
