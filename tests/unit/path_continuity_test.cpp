#include "capture/path_continuity.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace npt::capture {
namespace {

// Images named in time order on a circle of radius 4, 5 degrees apart; identity rotation, so the centre is
// -tvec.
ColmapModel circle_model(int n) {
    ColmapModel m;
    for (int i = 0; i < n; ++i) {
        ColmapImage im;
        im.id = i + 1;
        im.camera_id = 1;
        char name[32];
        std::snprintf(name, sizeof name, "frame_%05d.png", i * 10);
        im.name = name;
        const double a = i * 5.0 * 3.14159265358979 / 180.0;
        im.tvec = {-4 * std::cos(a), -4 * std::sin(a), 0};
        m.images.push_back(im);
    }
    return m;
}

TEST(PathContinuity, ASmoothPathHasNoJumps) { EXPECT_TRUE(find_path_jumps(circle_model(40)).empty()); }

TEST(PathContinuity, APieceOnTheWrongSideIsFound) {
    ColmapModel m = circle_model(40);
    // Frames 20..29 placed on the opposite side of the object, as a mirrored match does.
    for (int i = 20; i < 30; ++i)
        m.images[size_t(i)].tvec = {-m.images[size_t(i)].tvec[0], -m.images[size_t(i)].tvec[1], 0};
    // Shuffled order in the model: the check sorts by name.
    std::swap(m.images[3], m.images[35]);
    const auto jumps = find_path_jumps(m);
    ASSERT_EQ(jumps.size(), 2u);
    EXPECT_EQ(jumps[0].from, "frame_00190.png");
    EXPECT_EQ(jumps[0].to, "frame_00200.png");
    EXPECT_EQ(jumps[1].from, "frame_00290.png");
    EXPECT_GT(jumps[0].ratio, 8.0);
    EXPECT_NEAR(jumps[0].step / (2 * 4 * std::sin(2.5 * 3.14159265358979 / 180.0)), jumps[0].ratio, 1e-9);
}

TEST(PathContinuity, TooFewImagesGiveNoVerdict) { EXPECT_TRUE(find_path_jumps(circle_model(2)).empty()); }

// Poses along the x axis, one unit apart, with a leap of 50 after each index in `leaps_after`.
std::vector<CameraPose> line_poses(int n, std::vector<int> leaps_after) {
    std::vector<CameraPose> poses;
    double x = 0;
    for (int i = 0; i < n; ++i) {
        CameraPose p;
        char name[32];
        std::snprintf(name, sizeof name, "%04d.jpg", i);
        p.name = name;
        p.centre = {x, 0, 0};
        poses.push_back(p);
        x += std::find(leaps_after.begin(), leaps_after.end(), i) != leaps_after.end() ? 50 : 1;
    }
    return poses;
}

TEST(PathContinuity, PoseListJumpsAreFound) {
    const auto jumps = find_path_jumps(line_poses(12, {3, 7}));
    ASSERT_EQ(jumps.size(), 2u);
    EXPECT_EQ(jumps[0].from, "0003.jpg");
    EXPECT_EQ(jumps[0].to, "0004.jpg");
    EXPECT_DOUBLE_EQ(jumps[0].step, 50);
    EXPECT_DOUBLE_EQ(jumps[0].ratio, 50);
    EXPECT_EQ(jumps[1].from, "0007.jpg");
    // A higher factor lets the same leaps pass.
    EXPECT_TRUE(find_path_jumps(line_poses(12, {3, 7}), 60).empty());
}

TEST(PathContinuity, PiecesAreCutAtTheJumps) {
    using Pieces = std::vector<std::pair<size_t, size_t>>;
    EXPECT_EQ(continuous_pieces(line_poses(12, {3, 7})), (Pieces{{0, 4}, {4, 8}, {8, 12}}));
    EXPECT_EQ(continuous_pieces(line_poses(12, {})), (Pieces{{0, 12}}));
    // A leap out of the first or into the last image leaves a piece of one.
    EXPECT_EQ(continuous_pieces(line_poses(6, {0, 4})), (Pieces{{0, 1}, {1, 5}, {5, 6}}));
    EXPECT_EQ(continuous_pieces(line_poses(2, {0})), (Pieces{{0, 2}}));  // too few for a verdict
    EXPECT_TRUE(continuous_pieces({}).empty());
}

}  // namespace
}  // namespace npt::capture
