// Ray marching (nerf/ray_march.h): samples only in occupied cells and covering an occupied block's chord,
// step sizes with and without cone angle, cascade selection (position and step size), misses, rays starting
// inside, axis-parallel rays and rays on cell boundaries, and non-finite or degenerate input.
#include "nerf/ray_march.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "nerf/occupancy_grid.h"

namespace npt::nerf {
namespace {

// A one-cascade grid of R^3 cells with the cells [lo, hi)^3 occupied.
struct BlockGrid {
    int resolution;
    int lo, hi;
    std::vector<uint8_t> occupied;
    BlockGrid(int r, int lo_, int hi_) : resolution(r), lo(lo_), hi(hi_), occupied(size_t(r) * r * r, 0) {
        for (int z = lo; z < hi; ++z)
            for (int y = lo; y < hi; ++y)
                for (int x = lo; x < hi; ++x) occupied[size_t(x) + size_t(y) * r + size_t(z) * r * r] = 1;
    }
    OccupancyGridView view() const { return {occupied.data(), 1, resolution}; }
    Vec3 box_min() const { return Vec3(float(lo) / float(resolution)); }
    Vec3 box_max() const { return Vec3(float(hi) / float(resolution)); }
};

// Length of the ray's chord through [bmin, bmax] (0 when it misses), in double.
double chord(Vec3 bmin, Vec3 bmax, const Ray& ray) {
    double lo = 0, hi = 1e300;
    for (int a = 0; a < 3; ++a) {
        if (ray.d[a] == 0.0f) {
            if (ray.o[a] < bmin[a] || ray.o[a] >= bmax[a]) return 0;
            continue;
        }
        const double t0 = (double(bmin[a]) - ray.o[a]) / ray.d[a];
        const double t1 = (double(bmax[a]) - ray.o[a]) / ray.d[a];
        lo = std::max(lo, std::min(t0, t1));
        hi = std::min(hi, std::max(t0, t1));
    }
    return hi > lo ? hi - lo : 0;
}

std::vector<MarchSample> march(const MarchParams& mp, const OccupancyGridView& grid, const Ray& ray,
                               float jitter) {
    std::vector<MarchSample> out(size_t(std::max(mp.max_samples, 0)));
    out.resize(size_t(march_ray(mp, grid, ray, jitter, out.data())));
    return out;
}

// Every sample in an occupied cell, every sample within [t_near, t_far), t strictly increasing, and the
// samples' steps covering the block's chord to within one step (plus rounding of positions at the faces).
void check_block_ray(const BlockGrid& g, const MarchParams& mp, const Ray& ray, float jitter) {
    const std::vector<MarchSample> s = march(mp, g.view(), ray, jitter);
    float t_near = 0, t_far = 0;
    const bool hit = march_bounds(mp, ray, &t_near, &t_far);
    double length = 0;
    for (size_t i = 0; i < s.size(); ++i) {
        ASSERT_TRUE(g.view().is_occupied(s[i].position, 0)) << "sample " << i;
        ASSERT_TRUE(hit);
        EXPECT_GE(s[i].t, t_near);
        EXPECT_LT(s[i].t, t_far);
        EXPECT_EQ(s[i].dt, march_step(mp, s[i].t));
        if (i > 0) {
            EXPECT_GT(s[i].t, s[i - 1].t);
        }
        length += s[i].dt;
    }
    const double c = chord(g.box_min(), g.box_max(), ray);
    EXPECT_NEAR(length, c, mp.min_step + 1e-5) << "samples " << s.size();
}

TEST(RayMarch, BoundsSlabTest) {
    MarchParams mp;
    float tn = -1, tf = -1;
    ASSERT_TRUE(march_bounds(mp, Ray{Vec3(-1.0f, 0.5f, 0.5f), Vec3(1, 0, 0)}, &tn, &tf));
    EXPECT_FLOAT_EQ(tn, 1.0f);
    EXPECT_FLOAT_EQ(tf, 2.0f);
    // Starting inside: t_near is clipped to 0.
    ASSERT_TRUE(march_bounds(mp, Ray{Vec3(0.25f, 0.5f, 0.5f), Vec3(-1, 0, 0)}, &tn, &tf));
    EXPECT_EQ(tn, 0.0f);
    EXPECT_FLOAT_EQ(tf, 0.25f);
    // Behind the origin, beside the box, and parallel to a slab outside it: misses.
    EXPECT_FALSE(march_bounds(mp, Ray{Vec3(2.0f, 0.5f, 0.5f), Vec3(1, 0, 0)}, &tn, &tf));
    EXPECT_FALSE(march_bounds(mp, Ray{Vec3(-1.0f, 1.5f, 0.5f), normalize(Vec3(1, 0.1f, 0))}, &tn, &tf));
    EXPECT_FALSE(march_bounds(mp, Ray{Vec3(-1.0f, 1.01f, 0.5f), Vec3(1, 0, 0)}, &tn, &tf));
    // Parallel to a slab exactly on its face: inside (the box is closed), no NaN from 0 * inf.
    ASSERT_TRUE(march_bounds(mp, Ray{Vec3(-1.0f, 1.0f, 0.0f), Vec3(1, 0, 0)}, &tn, &tf));
    EXPECT_FLOAT_EQ(tn, 1.0f);
    EXPECT_FLOAT_EQ(tf, 2.0f);
}

TEST(RayMarch, SamplesOnlyInOccupiedBlockAndCoverItsChord) {
    const BlockGrid g(16, 4, 8);  // occupied: [0.25, 0.5)^3
    MarchParams mp;               // aabb [0,1]^3, dt = sqrt(3)/1024, no cone
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    for (int i = 0; i < 300; ++i) {
        // From a random point outside (or inside) the aabb towards a random point in the block.
        const Vec3 o(3 * u(rng) - 1, 3 * u(rng) - 1, 3 * u(rng) - 1);
        const Vec3 target = g.box_min() + Vec3(u(rng), u(rng), u(rng)) * 0.25f;
        const Ray ray{o, normalize(target - o)};
        check_block_ray(g, mp, ray, u(rng));
        if (HasFatalFailure() || HasFailure()) {
            ADD_FAILURE() << "ray " << i;
            return;
        }
    }
}

TEST(RayMarch, AxisParallelRaysAndCellBoundaries) {
    const BlockGrid g(16, 4, 8);
    MarchParams mp;
    const float j = 0.37f;
    // Directions with zero components, from outside, from inside the block, and from inside empty space.
    check_block_ray(g, mp, Ray{Vec3(-0.5f, 0.3f, 0.4f), Vec3(1, 0, 0)}, j);
    check_block_ray(g, mp, Ray{Vec3(0.3f, 1.5f, 0.4f), Vec3(0, -1, 0)}, j);
    check_block_ray(g, mp, Ray{Vec3(0.3f, 0.3f, 0.3f), Vec3(0, 0, 1)}, j);
    check_block_ray(g, mp, Ray{Vec3(0.9f, 0.3f, 0.4f), Vec3(-1, 0, 0)}, j);
    check_block_ray(g, mp, Ray{Vec3(0.9f, 0.9f, 0.4f), normalize(Vec3(-1, -1, 0))}, j);
    // Origin exactly on the block's far face, moving into it: the distance to the exit of the empty cell
    // there is 0, and marching must still step into the block.
    check_block_ray(g, mp, Ray{Vec3(0.5f, 0.3f, 0.3f), Vec3(-1, 0, 0)}, 0.0f);
    EXPECT_GT(march(mp, g.view(), Ray{Vec3(0.5f, 0.3f, 0.3f), Vec3(-1, 0, 0)}, 0.0f).size(), 100u);
    // Along a line of cell boundaries (y and z on boundaries) and along the block's edge.
    check_block_ray(g, mp, Ray{Vec3(-0.1f, 0.375f, 0.25f), Vec3(1, 0, 0)}, j);
    // Parallel to the block, beside it: no samples.
    EXPECT_TRUE(march(mp, g.view(), Ray{Vec3(-0.5f, 0.6f, 0.4f), Vec3(1, 0, 0)}, j).empty());
}

TEST(RayMarch, StepWithoutConeAngleIsConstant) {
    MarchParams mp;
    mp.max_samples = 4096;
    const OccupancyGridView all{nullptr, 1, 128};  // no occupancy array: every cell occupied
    const Ray ray{Vec3(-1.0f, 0.5f, 0.5f), Vec3(1, 0, 0)};
    const float jitter = 0.5f;
    const std::vector<MarchSample> s = march(mp, all, ray, jitter);
    ASSERT_FALSE(s.empty());
    EXPECT_FLOAT_EQ(s[0].t, 1.0f + jitter * mp.min_step);
    for (size_t i = 0; i < s.size(); ++i) {
        EXPECT_EQ(s[i].dt, mp.min_step);
        // The lattice t0 + i dt, computed directly (no rounding accumulates along the ray).
        EXPECT_EQ(s[i].t, s[0].t + float(i) * mp.min_step);
        if (i > 0) {
            EXPECT_NEAR(s[i].t - s[i - 1].t, s[i - 1].dt, 1e-6f);
        }
    }
    // The unit length is covered: floor or ceil of 1 / dt samples, the last one within one step of the exit.
    EXPECT_NEAR(double(s.size()), 1.0 / mp.min_step, 1.0);
    EXPECT_GT(s.back().t + s.back().dt, 2.0f - 1e-5f);
}

TEST(RayMarch, ConeAngleStepGrowsWithDistanceAndIsClamped) {
    // aabb_scale 16 (instant-ngp's large scenes): 5 cascades, cone angle 1/256, steps from sqrt(3)/1024 to
    // a maximum reached inside the aabb.
    const int cascades = cascades_for_aabb_scale(16.0f);
    ASSERT_EQ(cascades, 5);
    MarchParams mp;
    mp.aabb_min = Vec3(0.5f - 8.0f);
    mp.aabb_max = Vec3(0.5f + 8.0f);
    mp.cone_angle = 1.0f / 256.0f;
    mp.max_step = 0.02f;  // reached at t = 5.12, inside this aabb (sqrt(3) * 16 / 128 would need t = 55)
    mp.max_samples = 100000;
    const OccupancyGridView all{nullptr, cascades, 128};
    const Ray ray{Vec3(0.5f, 0.5f, 0.5f), normalize(Vec3(1, 0.7f, 0.3f))};  // from the centre outwards
    const std::vector<MarchSample> s = march(mp, all, ray, 0.25f);
    ASSERT_GT(s.size(), 10u);
    bool saw_min = false, saw_cone = false, saw_max = false;
    for (size_t i = 0; i < s.size(); ++i) {
        const float expect = std::min(std::max(s[i].t / 256.0f, mp.min_step), mp.max_step);
        EXPECT_EQ(s[i].dt, expect);
        if (i > 0) {
            EXPECT_EQ(s[i].t, s[i - 1].t + s[i - 1].dt);
            EXPECT_GE(s[i].dt, s[i - 1].dt);
        }
        saw_min |= s[i].dt == mp.min_step;
        saw_max |= s[i].dt == mp.max_step;
        saw_cone |= s[i].dt > mp.min_step && s[i].dt < mp.max_step;
    }
    EXPECT_TRUE(saw_min && saw_cone && saw_max);
}

TEST(RayMarch, CascadesForAabbScale4) {
    EXPECT_EQ(cascades_for_aabb_scale(1.0f), 1);
    EXPECT_EQ(cascades_for_aabb_scale(0.5f), 1);
    EXPECT_EQ(cascades_for_aabb_scale(2.0f), 2);
    EXPECT_EQ(cascades_for_aabb_scale(3.0f), 3);
    EXPECT_EQ(cascades_for_aabb_scale(4.0f), 3);
    EXPECT_EQ(cascades_for_aabb_scale(16.0f), 5);
    EXPECT_EQ(cascades_for_aabb_scale(128.0f), 8);

    const int r = 128;
    const OccupancyGridView v{nullptr, cascades_for_aabb_scale(4.0f), r};  // cascades of side 1, 2, 4
    EXPECT_EQ(v.cascade_of(Vec3(0.5f, 0.5f, 0.5f)), 0);
    EXPECT_EQ(v.cascade_of(Vec3(0.9f, 0.1f, 0.5f)), 0);
    EXPECT_EQ(v.cascade_of(Vec3(1.0f, 0.5f, 0.5f)), 1);  // on cascade 0's face: outside its half-open cells
    EXPECT_EQ(v.cascade_of(Vec3(0.5f, -0.4f, 0.5f)), 1);
    EXPECT_EQ(v.cascade_of(Vec3(0.5f, 0.5f, 2.0f)), 2);
    EXPECT_EQ(v.cascade_of(Vec3(-1.4f, 0.5f, 0.5f)), 2);
    EXPECT_EQ(v.cascade_of(Vec3(9.0f, 0.5f, 0.5f)), 2);  // clamped to the last cascade

    const int64_t r3 = int64_t(r) * r * r;
    EXPECT_EQ(v.cell_index(Vec3(0.5f, 0.5f, 0.5f), 0), 64 + 64 * r + 64 * int64_t(r) * r);
    EXPECT_EQ(v.cell_index(Vec3(0.0f, 0.0f, 0.0f), 0), 0);
    EXPECT_EQ(v.cell_index(Vec3(1.0f, 0.5f, 0.5f), 0), -1);
    // Cascade 1 spans [-0.5, 1.5): the origin is cell 32 on every axis.
    EXPECT_EQ(v.cell_index(Vec3(0.0f, 0.0f, 0.0f), 1), r3 + 32 + 32 * r + 32 * int64_t(r) * r);
    // Cascade 2 spans [-1.5, 2.5): cell size 1/32.
    EXPECT_EQ(v.cell_index(Vec3(-1.5f, -1.5f, -1.5f), 2), 2 * r3);
    EXPECT_EQ(v.cell_index(Vec3(2.49f, -1.5f, -1.5f), 2), 2 * r3 + 127);
    EXPECT_EQ(v.cell_index(Vec3(-1.5f, 2.0f, -1.5f), 2), 2 * r3 + 112 * r);
    EXPECT_EQ(v.cell_index(Vec3(2.5f, 0.5f, 0.5f), 2), -1);

    // The cascade a march tests: that of the position, or a coarser one whose cells are longer than dt.
    EXPECT_EQ(march_cascade(v, Vec3(0.5f), 0.9f / r), 0);
    EXPECT_EQ(march_cascade(v, Vec3(0.5f), 1.0f / r), 0);  // a step of exactly one cell
    EXPECT_EQ(march_cascade(v, Vec3(0.5f), 1.5f / r), 1);
    EXPECT_EQ(march_cascade(v, Vec3(0.5f), 2.0f / r), 1);
    EXPECT_EQ(march_cascade(v, Vec3(0.5f), 3.0f / r), 2);
    EXPECT_EQ(march_cascade(v, Vec3(0.5f), 100.0f / r), 2);
    EXPECT_EQ(march_cascade(v, Vec3(1.2f, 0.5f, 0.5f), 0.5f / r), 1);
}

TEST(RayMarch, StepSizeSelectsCoarserCascade) {
    // Cascade 0 all empty, cascades 1 and 2 all occupied: steps shorter than a cascade-0 cell skip the inner
    // cube; steps longer than one test cascade 1 there and sample it.
    const int r = 16;
    std::vector<uint8_t> occ(3 * size_t(r) * r * r, 1);
    std::fill(occ.begin(), occ.begin() + size_t(r) * r * r, 0);
    const OccupancyGridView v{occ.data(), 3, r};
    MarchParams mp;
    mp.aabb_min = Vec3(-1.5f);
    mp.aabb_max = Vec3(2.5f);
    mp.max_samples = 100000;
    const Ray ray{Vec3(-1.5f, 0.5f, 0.5f), Vec3(1, 0, 0)};
    mp.min_step = mp.max_step = 0.5f / r;  // half a cascade-0 cell
    for (const MarchSample& s : march(mp, v, ray, 0.5f))
        EXPECT_TRUE(s.position.x < 0.0f || s.position.x >= 1.0f) << s.position.x;
    mp.min_step = mp.max_step = 1.5f / r;
    int inner = 0;
    for (const MarchSample& s : march(mp, v, ray, 0.5f)) inner += s.position.x >= 0.0f && s.position.x < 1.0f;
    EXPECT_GE(inner, int(1.0f / mp.min_step) - 1);
}

TEST(RayMarch, MissesAndMaxSamples) {
    const BlockGrid g(16, 0, 16);  // all occupied
    MarchParams mp;
    EXPECT_TRUE(march(mp, g.view(), Ray{Vec3(-1, 0.5f, 0.5f), Vec3(-1, 0, 0)}, 0.5f).empty());
    EXPECT_TRUE(march(mp, g.view(), Ray{Vec3(-1, 2.0f, 0.5f), normalize(Vec3(1, 0.2f, 0))}, 0.5f).empty());
    mp.max_samples = 10;
    EXPECT_EQ(march(mp, g.view(), Ray{Vec3(-1, 0.5f, 0.5f), Vec3(1, 0, 0)}, 0.5f).size(), 10u);
    mp.max_samples = 0;
    EXPECT_TRUE(march(mp, g.view(), Ray{Vec3(-1, 0.5f, 0.5f), Vec3(1, 0, 0)}, 0.5f).empty());
}

TEST(RayMarch, StartsInside) {
    const BlockGrid g(16, 0, 16);
    MarchParams mp;
    const Ray ray{Vec3(0.5f, 0.5f, 0.5f), normalize(Vec3(0.3f, -1, 0.2f))};
    const std::vector<MarchSample> s = march(mp, g.view(), ray, 0.25f);
    ASSERT_FALSE(s.empty());
    EXPECT_FLOAT_EQ(s[0].t, 0.25f * mp.min_step);
    float tn = 0, tf = 0;
    ASSERT_TRUE(march_bounds(mp, ray, &tn, &tf));
    EXPECT_NEAR(s.size() * mp.min_step, tf, mp.min_step);
}

TEST(RayMarch, NonFiniteAndDegenerateInputGiveNoSamples) {
    const BlockGrid g(16, 0, 16);
    MarchParams mp;
    const float nan = std::nanf("");
    const float inf = INFINITY;
    const Vec3 o(-1, 0.5f, 0.5f), d(1, 0, 0);
    EXPECT_TRUE(march(mp, g.view(), Ray{Vec3(nan, 0.5f, 0.5f), d}, 0.5f).empty());
    EXPECT_TRUE(march(mp, g.view(), Ray{o, Vec3(nan, 0, 0)}, 0.5f).empty());
    EXPECT_TRUE(march(mp, g.view(), Ray{o, Vec3(1, nan, 0)}, 0.5f).empty());
    EXPECT_TRUE(march(mp, g.view(), Ray{o, Vec3(inf, 0, 0)}, 0.5f).empty());
    EXPECT_TRUE(march(mp, g.view(), Ray{Vec3(-inf, 0.5f, 0.5f), d}, 0.5f).empty());
    EXPECT_TRUE(march(mp, g.view(), Ray{o, d}, nan).empty());
    EXPECT_TRUE(march(mp, g.view(), Ray{Vec3(0.5f), Vec3(0, 0, 0)}, 0.5f).empty());  // zero direction
    MarchParams bad = mp;
    bad.min_step = 0.0f;
    EXPECT_TRUE(march(bad, g.view(), Ray{o, d}, 0.5f).empty());
    bad = mp;
    bad.min_step = nan;
    EXPECT_TRUE(march(bad, g.view(), Ray{o, d}, 0.5f).empty());
    bad = mp;
    bad.aabb_max = Vec3(inf);
    EXPECT_TRUE(march(bad, g.view(), Ray{o, d}, 0.5f).empty());
}

TEST(RayMarch, TerminatesWhereStepsNoLongerChangeT) {
    // So far away that t + dt == t: the march must stop instead of looping.
    const BlockGrid empty(16, 0, 0);
    const BlockGrid full(16, 0, 16);
    MarchParams mp;
    for (float far : {-1e7f, -1e30f}) {
        const Ray ray{Vec3(far, 0.5f, 0.5f), Vec3(1, 0, 0)};
        EXPECT_LE(march(mp, full.view(), ray, 0.5f).size(), 1u);
        EXPECT_TRUE(march(mp, empty.view(), ray, 0.5f).empty());
    }
}

}  // namespace
}  // namespace npt::nerf
