#include "core/sobol_sampler.h"

#include <gtest/gtest.h>

#include <set>
#include <vector>

namespace npt {
namespace {

// The first 2^m points of an Owen-scrambled 2D Sobol sequence form a (0, m, 2)-net: every elementary interval
// of area 2^-m (here 1x64, 2x32, ..., 64x1 grids) holds exactly one point. A wrong direction number, a
// scramble that breaks nesting or a shuffle that is not a permutation of the index all violate this.
TEST(SobolSampler, EachScrambledPairIsA02Net) {
    const int n = 64;
    for (uint32_t px : {0u, 17u, 1234u})
        for (int dim = 0; dim < int(k_sobol_dimensions) / 2 + 1; ++dim) {
            std::vector<Vec2> pts;
            for (int s = 0; s < n; ++s) {
                SobolSampler sampler(42, px, 7, uint32_t(s));
                Vec2 p;
                for (int d = 0; d <= dim; ++d) p = sampler.next_2d();
                ASSERT_GE(p.x, 0.0f);
                ASSERT_LT(p.x, 1.0f);
                ASSERT_GE(p.y, 0.0f);
                ASSERT_LT(p.y, 1.0f);
                pts.push_back(p);
            }
            for (int bx = 1; bx <= n; bx *= 2) {
                int by = n / bx;
                std::set<int> cells;
                for (Vec2 p : pts) cells.insert(int(p.x * float(bx)) * by + int(p.y * float(by)));
                EXPECT_EQ(int(cells.size()), n)
                    << "grid " << bx << "x" << by << " pixel " << px << " pair " << dim;
            }
        }
}

TEST(SobolSampler, PixelsAndSeedsAreDecorrelated) {
    SobolSampler a(1, 10, 10, 0), b(1, 11, 10, 0), c(2, 10, 10, 0);
    Vec2 pa = a.next_2d(), pb = b.next_2d(), pc = c.next_2d();
    EXPECT_NE(pa.x, pb.x);
    EXPECT_NE(pa.x, pc.x);
    SobolSampler a2(1, 10, 10, 0);
    EXPECT_EQ(a2.next_2d().x, pa.x);  // deterministic
}

// Past the Sobol dimensions the values come from PCG: their mean over many samples is 1/2 within 5 standard
// errors (1/sqrt(12 n)).
TEST(SobolSampler, LaterDimensionsAreUniform) {
    const int n = 20000;
    double sum = 0;
    for (int s = 0; s < n; ++s) {
        SobolSampler sampler(3, 5, 5, uint32_t(s));
        for (uint32_t d = 0; d < k_sobol_dimensions + 3; ++d) sampler.next_1d();
        sum += sampler.next_1d();
    }
    EXPECT_NEAR(sum / n, 0.5, 5.0 / std::sqrt(12.0 * n));
}

}  // namespace
}  // namespace npt
