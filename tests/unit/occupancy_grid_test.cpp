// Occupancy grid (nerf/occupancy_grid.h): fresh grids are fully occupied, update plans (warm-up, quarter plus
// occupied, positions inside their cells, determinism), the decayed-max update, the occupied threshold,
// learning a sphere from its density, and set_density's errors.
#include "nerf/occupancy_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "core/error.h"

namespace npt::nerf {
namespace {

constexpr float k_min_step = 1.7320508f / 1024.0f;

OccupancyConfig small_config(int resolution) {
    OccupancyConfig cfg;
    cfg.resolution = resolution;
    return cfg;  // decay 0.95, threshold 0.01, interval 16, warm-up 256 steps = 16 updates
}

// Corner of cell `cell`, and the cell's edge length, in model space.
void cell_box(const OccupancyGrid& g, uint32_t cell, Vec3* lo, float* size) {
    const uint32_t r = uint32_t(g.resolution());
    const uint32_t c = cell / (r * r * r), local = cell % (r * r * r);
    const float cs = float(1 << c);
    *size = cs / float(r);
    *lo = Vec3(0.5f - 0.5f * cs) +
          Vec3(float(local % r), float((local / r) % r), float(local / (r * r))) * *size;
}

TEST(Occupancy, FreshGridIsFullyOccupied) {
    const OccupancyGrid g(3, 16);
    EXPECT_EQ(g.cell_count(), 3u * 16 * 16 * 16);
    EXPECT_EQ(g.occupied_fraction(), 1.0);
    for (float d : g.density()) EXPECT_EQ(d, 0.0f);  // no estimate yet, yet occupied: nothing is skipped
    const OccupancyGridView v = g.view();
    EXPECT_TRUE(v.is_occupied(Vec3(0.5f), 0));
    EXPECT_TRUE(v.is_occupied(Vec3(2.4f, -1.4f, 0.5f), 2));
    EXPECT_EQ(OccupancyGrid().occupied_fraction(), 0.0);
    EXPECT_THROW(OccupancyGrid(0, 16), Error);
    EXPECT_THROW(OccupancyGrid(9, 16), Error);
    EXPECT_THROW(OccupancyGrid(1, 15), Error);
    EXPECT_THROW(OccupancyGrid(8, 1024), Error);  // 2^33 cells
}

TEST(Occupancy, CascadesForAabbScaleRejectsBadScales) {
    EXPECT_THROW(cascades_for_aabb_scale(0.0f), Error);
    EXPECT_THROW(cascades_for_aabb_scale(-4.0f), Error);
    EXPECT_THROW(cascades_for_aabb_scale(std::nanf("")), Error);
    EXPECT_THROW(cascades_for_aabb_scale(INFINITY), Error);
    EXPECT_THROW(cascades_for_aabb_scale(256.0f), Error);
}

TEST(Occupancy, WarmupPlansEveryCellOncePerCascadeCountUpdatesThenAQuarterPlusOccupied) {
    OccupancyGrid g(2, 8);
    const OccupancyConfig cfg = small_config(8);
    const uint32_t n = uint32_t(g.cell_count());
    Pcg32 rng(1, 2);
    std::vector<uint32_t> cells;
    std::vector<Vec3> pos;
    std::vector<int> times_planned(n, 0);
    for (int update = 14; update < 16; ++update) {  // 15 * 16 < 256: still warm-up; two cascades, two turns
        g.plan_update(cfg, update, rng, cells, pos);
        ASSERT_EQ(cells.size(), n / 2);
        ASSERT_EQ(pos.size(), cells.size());
        for (uint32_t c : cells) ++times_planned[c];
    }
    for (uint32_t i = 0; i < n; ++i) ASSERT_EQ(times_planned[i], 1) << "cell " << i;
    OccupancyGrid one(1, 8);  // one cascade: every cell every time, as instant-ngp
    one.plan_update(cfg, 15, rng, cells, pos);
    ASSERT_EQ(cells.size(), one.cell_count());

    // Leave only the cells of cascade 0 with x < 2 occupied, then plan a post-warm-up update.
    std::vector<float> density(n, 0.0f);
    std::set<uint32_t> occupied;
    for (uint32_t i = 0; i < n / 2; ++i)
        if (i % 8 < 2) {
            density[i] = 1.0f;
            occupied.insert(i);
        }
    g.set_density(density, cfg.threshold);
    g.plan_update(cfg, 16, rng, cells, pos);
    ASSERT_EQ(cells.size(), 2 * size_t(n / 4));
    ASSERT_EQ(pos.size(), cells.size());
    for (size_t k = n / 4; k < cells.size(); ++k) EXPECT_EQ(occupied.count(cells[k]), 1u) << cells[k];
    // The uniform quarter reaches both cascades and empty cells.
    bool saw_cascade1 = false, saw_empty = false;
    for (size_t k = 0; k < n / 4; ++k) {
        saw_cascade1 |= cells[k] >= n / 2;
        saw_empty |= occupied.count(cells[k]) == 0;
    }
    EXPECT_TRUE(saw_cascade1 && saw_empty);

    // An all-empty grid plans only the uniform quarter (all-zero densities would mean "no estimate yet", which
    // counts as occupied, so the cells get a tiny value under an explicit threshold instead).
    g.set_density(std::vector<float>(n, 1e-9f), 1e-6f);
    g.plan_update(cfg, 100, rng, cells, pos);
    EXPECT_EQ(cells.size(), size_t(n / 4));
}

TEST(Occupancy, PlannedPositionsLieInTheirCellsAndAreDeterministic) {
    const OccupancyGrid g(3, 16);
    const OccupancyConfig cfg = small_config(16);
    for (int update : {0, 40}) {
        Pcg32 a(9, 4), b(9, 4);
        std::vector<uint32_t> ca, cb;
        std::vector<Vec3> pa, pb;
        g.plan_update(cfg, update, a, ca, pa);
        g.plan_update(cfg, update, b, cb, pb);
        ASSERT_EQ(ca, cb);
        ASSERT_EQ(pa.size(), ca.size());
        const OccupancyGridView v = g.view();
        const uint32_t r3 = 16 * 16 * 16;
        Vec3 mean_offset(0.0f);
        for (size_t k = 0; k < ca.size(); ++k) {
            ASSERT_EQ(pa[k].x, pb[k].x);
            ASSERT_EQ(pa[k].z, pb[k].z);
            ASSERT_EQ(v.cell_index(pa[k], int(ca[k] / r3)), int64_t(ca[k])) << k;
            Vec3 lo;
            float size;
            cell_box(g, ca[k], &lo, &size);
            mean_offset += (pa[k] - lo) / size;
        }
        // Uniform within the cell: the mean offset is 1/2 per axis, with a standard error of
        // sqrt(1/12 / N); 5 standard errors.
        mean_offset = mean_offset / float(ca.size());
        const float tol = 5.0f * std::sqrt(1.0f / 12.0f / float(ca.size()));
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(mean_offset[a], 0.5f, tol);
    }
}

TEST(Occupancy, UpdateIsDecayedMaxAndUnplannedCellsDecay) {
    OccupancyGrid g(1, 4);
    OccupancyConfig cfg = small_config(4);
    const size_t n = g.cell_count();
    std::vector<float> density(n, 0.5f);
    g.set_density(density, cfg.threshold);
    // Cell 3 is planned twice (the larger estimate wins, decay applies once); cell 5 gets an estimate
    // below its decayed value; cell 7 a NaN, which is ignored; the rest only decay.
    const std::vector<uint32_t> cells = {3, 3, 5, 7};
    const std::vector<float> sigma = {100.0f, 400.0f, 1.0f, std::nanf("")};
    g.apply_update(cfg, cells, sigma, k_min_step);
    const float decayed = 0.5f * cfg.decay;
    EXPECT_EQ(g.density()[3], 400.0f * k_min_step);
    EXPECT_EQ(g.density()[5], decayed);
    EXPECT_EQ(g.density()[7], decayed);
    EXPECT_EQ(g.density()[0], decayed);
    // Repeated empty updates decay geometrically.
    for (int k = 0; k < 10; ++k) g.apply_update(cfg, {}, {}, k_min_step);
    EXPECT_NEAR(g.density()[0], decayed * std::pow(cfg.decay, 10.0f), 1e-6f * decayed);
    EXPECT_THROW(g.apply_update(cfg, {1, 2}, {1.0f}, k_min_step), std::invalid_argument);
    EXPECT_THROW(g.apply_update(cfg, {uint32_t(n)}, {1.0f}, k_min_step), std::invalid_argument);
}

TEST(Occupancy, OccupiedUsesTheSmallerOfThresholdAndMean) {
    OccupancyGrid g(1, 2);  // 8 cells
    // Mean 0.25 > threshold 0.01: the threshold decides.
    g.set_density({0.0f, 0.005f, 0.02f, 0.0f, 0.0f, 0.0f, 0.0f, 1.975f}, 0.01f);
    EXPECT_FLOAT_EQ(g.mean_density(), 0.25f);
    EXPECT_EQ(g.occupied_fraction(), 2.0 / 8.0);
    // Mean 0.001 < threshold: cells above the mean are occupied.
    g.set_density({0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.002f, 0.006f}, 0.01f);
    EXPECT_FLOAT_EQ(g.mean_density(), 0.001f);
    EXPECT_EQ(g.occupied_fraction(), 2.0 / 8.0);
    EXPECT_TRUE(g.view().is_occupied(Vec3(0.75f, 0.75f, 0.75f), 0));
    EXPECT_FALSE(g.view().is_occupied(Vec3(0.25f, 0.25f, 0.25f), 0));
}

TEST(Occupancy, LearnsASphereFromItsDensity) {
    // sigma = 100 inside the sphere of radius 0.25 about the centre, 0 outside; one estimate per planned cell
    // at its sampled position, as training does. 150 updates: the initial density decays to 0.95^150 = 5e-4,
    // below the mean (~0.007), while cells inside are re-estimated at 100 * min_step = 0.17 whenever planned.
    const int r = 16;
    OccupancyGrid g(2, r);
    const OccupancyConfig cfg = small_config(r);
    const Vec3 centre(0.5f);
    const float radius = 0.25f;
    auto sigma_at = [&](Vec3 p) { return length(p - centre) < radius ? 100.0f : 0.0f; };
    Pcg32 rng(1337, 0);
    std::vector<uint32_t> cells;
    std::vector<Vec3> pos;
    std::vector<float> sigma;
    for (int update = 0; update < 150; ++update) {
        g.plan_update(cfg, update, rng, cells, pos);
        sigma.resize(pos.size());
        for (size_t k = 0; k < pos.size(); ++k) sigma[k] = sigma_at(pos[k]);
        g.apply_update(cfg, cells, sigma, k_min_step);
    }
    const OccupancyGridView v = g.view();
    int inside = 0, outside = 0;
    for (uint32_t cell = 0; cell < g.cell_count(); ++cell) {
        Vec3 lo;
        float size;
        cell_box(g, cell, &lo, &size);
        // Nearest and farthest points of the cell from the centre.
        const Vec3 hi = lo + Vec3(size);
        const Vec3 nearest = vmin(vmax(centre, lo), hi);
        const Vec3 farthest(std::fabs(lo.x - 0.5f) > std::fabs(hi.x - 0.5f) ? lo.x : hi.x,
                            std::fabs(lo.y - 0.5f) > std::fabs(hi.y - 0.5f) ? lo.y : hi.y,
                            std::fabs(lo.z - 0.5f) > std::fabs(hi.z - 0.5f) ? lo.z : hi.z);
        const bool occupied = v.occupied[cell] != 0;
        if (length(farthest - centre) < radius) {
            EXPECT_TRUE(occupied) << "cell " << cell << " lies inside the sphere";
            ++inside;
        } else if (length(nearest - centre) >= radius) {
            EXPECT_FALSE(occupied) << "cell " << cell << " lies outside the sphere";
            ++outside;
        }
    }
    EXPECT_GT(inside, 100);  // the sphere covers ~4.2 % of cascade 0 (170 cells) and parts of cascade 1
    EXPECT_GT(outside, 7000);
    EXPECT_LT(g.occupied_fraction(), 0.1);
}

TEST(Occupancy, SetDensityRejectsWrongSizeAndNonFiniteValues) {
    OccupancyGrid g(2, 4);
    auto message = [&](std::vector<float> d) {
        try {
            g.set_density(std::move(d), 0.01f);
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    const std::string size_msg = message(std::vector<float>(100, 0.0f));
    EXPECT_NE(size_msg.find("'density'"), std::string::npos) << size_msg;
    EXPECT_NE(size_msg.find("100"), std::string::npos) << size_msg;
    EXPECT_NE(size_msg.find("128"), std::string::npos) << size_msg;
    EXPECT_EQ(size_msg.find('\n'), std::string::npos) << size_msg;
    for (float bad : {std::nanf(""), INFINITY, -INFINITY}) {
        std::vector<float> d(g.cell_count(), 0.1f);
        d[17] = bad;
        const std::string msg = message(d);
        EXPECT_NE(msg.find("'density'"), std::string::npos) << msg;
        EXPECT_NE(msg.find("17"), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
    // A failed restore leaves the grid as it was.
    EXPECT_EQ(g.occupied_fraction(), 1.0);
    EXPECT_EQ(g.density().size(), g.cell_count());
}

}  // namespace
}  // namespace npt::nerf
