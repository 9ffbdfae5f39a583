#include "capture/revisit_pairs.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace npt::capture {
namespace {

constexpr double k_pi = 3.14159265358979323846;

// `n` cameras walking `turns` times around the origin on a circle of radius 1 at constant height, each
// looking at the origin (OpenGL camera-to-world: -Z towards the origin, +Y up), named in walking order.
std::vector<CameraPose> walk(int n, double turns, double rise_per_turn = 0) {
    std::vector<CameraPose> poses;
    for (int i = 0; i < n; ++i) {
        const double a = 2 * k_pi * turns * i / n;
        CameraPose p;
        char name[32];
        std::snprintf(name, sizeof name, "frame_%05d.png", i);
        p.name = name;
        p.centre = {std::cos(a), std::sin(a), rise_per_turn * turns * i / n};
        const Eigen::Vector3d back = p.centre.normalized();  // +Z points away from what the camera sees
        const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
        const Eigen::Vector3d right = up.cross(back).normalized();
        p.rotation.col(0) = right;
        p.rotation.col(1) = back.cross(right);
        p.rotation.col(2) = back;
        poses.push_back(p);
    }
    return poses;
}

int index_of(const std::string& name) { return std::stoi(name.substr(6, 5)); }

TEST(RevisitPairs, AnOpenArcHasNone) {
    // Half a turn: no camera comes back near an earlier one.
    EXPECT_TRUE(revisit_pairs(walk(50, 0.5)).empty());
}

TEST(RevisitPairs, AClosedWalkPairsItsEndWithItsStart) {
    // 100 frames over one turn, 3.6 degrees apart: the last frames stand next to the first ones.
    const auto pairs = revisit_pairs(walk(100, 1.0));
    ASSERT_FALSE(pairs.empty());
    RevisitSettings s;
    for (const auto& [a, b] : pairs) {
        const int i = index_of(a), j = index_of(b);
        EXPECT_LT(i, j);
        EXPECT_GT(j - i, s.overlap);  // the sequential matcher matched the closer ones already
        // Near each other around the circle: the seam, within max_distance_steps steps.
        const int around = std::min(j - i, 100 - (j - i));
        EXPECT_LE(around, int(s.max_distance_steps)) << a << " " << b;
    }
    // Every frame within reach of the seam has partners, the nearest first: frame 0 pairs with 99.
    EXPECT_EQ(pairs.front().first, "frame_00000.png");
    bool has_0_99 = false;
    for (const auto& p : pairs) has_0_99 |= p.first == "frame_00000.png" && p.second == "frame_00099.png";
    EXPECT_TRUE(has_0_99);
}

TEST(RevisitPairs, ASecondTurnPairsWithTheFirstAndRespectsTheCap) {
    // Two turns: every frame of the second turn stands where a frame of the first stood, 50 frames earlier.
    RevisitSettings s;
    s.max_per_frame = 2;
    const auto pairs = revisit_pairs(walk(100, 2.0), s);
    ASSERT_FALSE(pairs.empty());
    for (const auto& [a, b] : pairs) {
        const int i = index_of(a), j = index_of(b);
        const int offset = (j - i) % 50;
        EXPECT_LE(std::min(offset, 50 - offset), int(s.max_distance_steps)) << a << " " << b;
    }
    // The same-place partner 50 frames away is the nearest and is always kept.
    for (int i = 0; i < 50; ++i) {
        bool found = false;
        for (const auto& [a, b] : pairs) found |= index_of(a) == i && index_of(b) == i + 50;
        EXPECT_TRUE(found) << i;
    }
    // With one partner per frame, each frame keeps only its nearest: the frame at its place on the other
    // turn, so exactly the 50 pairs (i, i + 50).
    s.max_per_frame = 1;
    const auto nearest = revisit_pairs(walk(100, 2.0), s);
    EXPECT_EQ(nearest.size(), 50u);
    for (const auto& [a, b] : nearest) EXPECT_EQ(index_of(b) - index_of(a), 50) << a << " " << b;
    EXPECT_GT(pairs.size(), nearest.size());
}

TEST(RevisitPairs, ViewsFacingAwayAreNotPaired) {
    // Two turns at the same places, but on the second the camera looks outwards (a person turned around): a
    // frame of one turn has no common view with the other turn, whatever the distance. Within a turn the
    // seam (its end next to its start) still pairs.
    std::vector<CameraPose> poses = walk(100, 2.0);
    for (size_t i = 50; i < 100; ++i) {
        poses[i].rotation.col(0) = -poses[i].rotation.col(0);
        poses[i].rotation.col(2) = -poses[i].rotation.col(2);
    }
    const auto pairs = revisit_pairs(poses);
    EXPECT_FALSE(pairs.empty());
    for (const auto& [a, b] : pairs) EXPECT_EQ(index_of(a) < 50, index_of(b) < 50) << a << " " << b;
}

TEST(RevisitPairs, TooFewPosesGiveNone) {
    EXPECT_TRUE(revisit_pairs(walk(10, 1.0)).empty());
    EXPECT_TRUE(revisit_pairs({}).empty());
}

}  // namespace
}  // namespace npt::capture
