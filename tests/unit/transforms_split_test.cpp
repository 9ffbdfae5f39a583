#include "capture/transforms_split.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <set>

#include "core/json_file.h"
#include "test_support.h"

namespace npt::capture {
namespace {
namespace fs = std::filesystem;

nlohmann::json frames_json(int n) {
    nlohmann::json root = {{"fl_x", 100.0}, {"w", 64}, {"h", 48}, {"aabb_scale", 16}};
    root["frames"] = nlohmann::json::array();
    // Written in reverse: the split must follow name order, not file order.
    for (int i = n - 1; i >= 0; --i)
        root["frames"].push_back(
            {{"file_path", "frames/frame_" + std::to_string(1000 + i) + ".png"},
             {"transform_matrix", {{1, 0, 0, i}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}}});
    return root;
}

TEST(TransformsSplit, HoldsOutEveryNthFrameInNameOrderAndKeepsTheRest) {
    const fs::path dir = test::temp_dir();
    test::write_file(dir / "transforms.json", frames_json(20).dump());
    const SplitCounts n = split_transforms(dir / "transforms.json", 8);
    const nlohmann::json train = read_json_file(dir / "transforms_train.json"),
                         test_split = read_json_file(dir / "transforms_test.json");
    // Frames 4 and 12 (every 8th from 8/2 = 4) are held out.
    EXPECT_EQ(n.test, 2u);
    EXPECT_EQ(n.train, 18u);
    ASSERT_EQ(test_split["frames"].size(), 2u);
    EXPECT_EQ(test_split["frames"][0]["file_path"], "frames/frame_1004.png");
    EXPECT_EQ(test_split["frames"][1]["file_path"], "frames/frame_1012.png");
    std::set<std::string> all;
    for (const auto* j : {&train, &test_split}) {
        EXPECT_EQ((*j)["fl_x"], 100.0);  // everything but the frames is copied
        EXPECT_EQ((*j)["aabb_scale"], 16);
        for (const auto& f : (*j)["frames"]) all.insert(f["file_path"].get<std::string>());
    }
    EXPECT_EQ(all.size(), 20u);  // no frame lost or duplicated
}

TEST(TransformsSplit, FewFramesStillHoldOneOut) {
    const fs::path dir = test::temp_dir();
    test::write_file(dir / "transforms.json", frames_json(3).dump());
    const SplitCounts n = split_transforms(dir / "transforms.json", 8);
    EXPECT_EQ(n.train, 2u);
    EXPECT_EQ(n.test, 1u);
}

TEST(TransformsSplit, BadInputIsAOneLineErrorNamingTheFile) {
    const fs::path dir = test::temp_dir();
    test::expect_error_message([&] { split_transforms(dir / "missing.json", 8); },
                               {"missing.json", "no such file"});
    test::write_file(dir / "bad.json", "{\"frames\": ");
    test::expect_error_message([&] { split_transforms(dir / "bad.json", 8); },
                               {"bad.json", "not valid JSON"});
    test::write_file(dir / "noframes.json", "{}");
    test::expect_error_message([&] { split_transforms(dir / "noframes.json", 8); },
                               {"noframes.json", "'frames'"});
    test::write_file(dir / "one.json", frames_json(1).dump());
    test::expect_error_message([&] { split_transforms(dir / "one.json", 8); }, {"one.json", "at least 2"});
    test::write_file(dir / "t.json", frames_json(5).dump());
    test::expect_error_message([&] { split_transforms(dir / "t.json", 1); }, {"t.json", "every >= 2"});
    EXPECT_FALSE(fs::exists(dir / "transforms_train.json"));  // nothing written on error
}

}  // namespace
}  // namespace npt::capture
