#include "capture/camera_rig.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>

#include "test_support.h"

namespace npt::capture {
namespace {
namespace fs = std::filesystem;

nlohmann::json frame_at(double x, double y, double z) {
    return {{"file_path", "f.png"},
            {"transform_matrix", {{1, 0, 0, x}, {0, 1, 0, y}, {0, 0, 1, z}, {0, 0, 0, 1}}}};
}

TEST(CameraRig, MediansOfDistanceAndElevationAndTheFieldOfView) {
    const fs::path dir = test::temp_dir();
    // Three cameras at distance 4 and elevations 0, 30, 90 deg, one outlier at distance 10: medians 4 and 30.
    const double s30 = std::sin(std::numbers::pi / 6), c30 = std::cos(std::numbers::pi / 6);
    nlohmann::json j = {{"fl_x", 50.0}, {"w", 100}, {"h", 80}};
    j["frames"] = {frame_at(4, 0, 0), frame_at(0, 4 * c30, 4 * s30), frame_at(0, 0, 4),
                   frame_at(0, 10 * c30, 10 * s30)};
    test::write_file(dir / "t.json", j.dump());
    const RigSummary rig = summarize_rig(dir / "t.json");
    EXPECT_EQ(rig.cameras, 4u);
    EXPECT_NEAR(rig.median_distance, 4.0, 1e-9);
    EXPECT_NEAR(rig.median_elevation_deg, 30.0, 1e-9);
    EXPECT_NEAR(rig.fov_x_deg, 90.0, 1e-9);  // w / 2 = fl_x
    EXPECT_EQ(rig.width, 100);
    EXPECT_EQ(rig.height, 80);

    j.erase("fl_x");
    j["camera_angle_x"] = 0.5;  // NeRF-synthetic style
    test::write_file(dir / "a.json", j.dump());
    EXPECT_NEAR(summarize_rig(dir / "a.json").fov_x_deg, 0.5 * 180 / std::numbers::pi, 1e-9);
}

TEST(CameraRig, BadInputNamesTheFileAndField) {
    const fs::path dir = test::temp_dir();
    test::expect_error_message([&] { summarize_rig(dir / "none.json"); }, {"none.json", "no such file"});
    test::write_file(dir / "e.json", R"({"frames": []})");
    test::expect_error_message([&] { summarize_rig(dir / "e.json"); }, {"e.json", "'frames'"});
    test::write_file(dir / "m.json",
                     R"({"w": 4, "h": 4, "fl_x": 2, "frames": [{"transform_matrix": [[1, 0]]}]})");
    test::expect_error_message([&] { summarize_rig(dir / "m.json"); },
                               {"m.json", "frames[0]", "transform_matrix"});
    nlohmann::json j = {{"w", 4}, {"h", 4}};
    j["frames"] = nlohmann::json::array({frame_at(1, 0, 0)});  // {x} alone is a copy of x for clang (CWG 2137)
    test::write_file(dir / "f.json", j.dump());
    test::expect_error_message([&] { summarize_rig(dir / "f.json"); }, {"f.json", "fl_x"});
    j["fl_x"] = -1;
    test::write_file(dir / "n.json", j.dump());
    test::expect_error_message([&] { summarize_rig(dir / "n.json"); }, {"n.json", "'fl_x'", "positive"});
}

}  // namespace
}  // namespace npt::capture
