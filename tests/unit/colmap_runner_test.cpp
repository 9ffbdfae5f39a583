#include "capture/colmap_runner.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <thread>
#include <vector>

#include "core/error.h"

namespace npt::capture {
namespace {

// The value after `key` in an argument list, or "" when the key is not there.
std::string value_of(const std::vector<std::string>& args, const std::string& key) {
    const auto it = std::find(args.begin(), args.end(), key);
    return it == args.end() || it + 1 == args.end() ? std::string() : *(it + 1);
}

bool mentions(const std::vector<std::string>& args, const std::string& prefix) {
    return std::any_of(args.begin(), args.end(),
                       [&](const std::string& a) { return a.rfind(prefix, 0) == 0; });
}

TEST(ColmapRunner, QualityNamesRoundTrip) {
    for (PosesQuality q : {PosesQuality::Fast, PosesQuality::Balanced, PosesQuality::Best})
        EXPECT_EQ(parse_poses_quality(poses_quality_name(q)), q);
    EXPECT_THROW(parse_poses_quality("fastest"), Error);
    EXPECT_THROW(parse_poses_quality(""), Error);
}

TEST(ColmapRunner, BestIsColmapsOwnSettingsWithExplicitThreads) {
    ColmapSettings s;
    s.quality = PosesQuality::Best;
    s.threads = 3;
    const ColmapStepOptions o = colmap_step_options(s, 540, 960);
    EXPECT_EQ(value_of(o.extraction, "--SiftExtraction.num_threads"), "3");
    EXPECT_EQ(value_of(o.matching, "--SiftMatching.num_threads"), "3");
    EXPECT_EQ(value_of(o.mapping, "--Mapper.num_threads"), "3");
    EXPECT_EQ(value_of(o.extraction, "--SiftExtraction.max_image_size"), "1600");
    EXPECT_FALSE(mentions(o.extraction, "--SiftExtraction.first_octave"));
    EXPECT_FALSE(mentions(o.extraction, "--SiftExtraction.max_num_features"));
    EXPECT_FALSE(mentions(o.matching, "--SiftMatching.max_num_matches"));
    EXPECT_FALSE(mentions(o.mapping, "--Mapper.ba_"));
    EXPECT_EQ(o.max_num_features, 8192);  // COLMAP's default
}

TEST(ColmapRunner, ThreadsDefaultToTheHardware) {
    ColmapSettings s;  // threads 0
    const ColmapStepOptions o = colmap_step_options(s, 540, 960);
    EXPECT_EQ(value_of(o.extraction, "--SiftExtraction.num_threads"),
              std::to_string(std::max(1, int(std::thread::hardware_concurrency()))));
    EXPECT_EQ(value_of(o.extraction, "--SiftExtraction.num_threads"),
              value_of(o.mapping, "--Mapper.num_threads"));
}

TEST(ColmapRunner, FasterQualitiesBudgetFeaturesByFrameSize) {
    for (PosesQuality q : {PosesQuality::Fast, PosesQuality::Balanced}) {
        ColmapSettings s;
        s.quality = q;
        const ColmapStepOptions phone = colmap_step_options(s, 540, 960);
        const ColmapStepOptions hd = colmap_step_options(s, 720, 1280);
        const ColmapStepOptions uhd = colmap_step_options(s, 2160, 3840);
        SCOPED_TRACE(poses_quality_name(q));
        EXPECT_LT(phone.max_num_features, hd.max_num_features);
        EXPECT_LE(hd.max_num_features, uhd.max_num_features);
        EXPECT_LE(uhd.max_num_features, 8192);
        // A 4K frame is shrunk to max_image_size first: its budget is that of a 1600-pixel frame.
        EXPECT_EQ(uhd.max_num_features, colmap_step_options(s, 900, 1600).max_num_features);
        EXPECT_EQ(value_of(hd.extraction, "--SiftExtraction.max_num_features"),
                  std::to_string(hd.max_num_features));
        EXPECT_EQ(value_of(hd.matching, "--SiftMatching.max_num_matches"),
                  std::to_string(hd.max_num_features));
        EXPECT_TRUE(mentions(hd.mapping, "--Mapper.ba_global_images_ratio"));
        EXPECT_TRUE(mentions(hd.mapping, "--Mapper.ba_local_max_num_iterations"));
        EXPECT_EQ(value_of(hd.mapping, "--Mapper.filter_max_reproj_error"), "2");
    }
    // The measured budgets (docs/benchmarks.md): fast 8000 per megapixel at the frame's size (every scale
    // level of a 540x960 frame), balanced 2000 per megapixel of the doubled frame.
    ColmapSettings fast;
    EXPECT_EQ(colmap_step_options(fast, 540, 960).max_num_features, 4147);
    EXPECT_EQ(colmap_step_options(fast, 720, 1280).max_num_features, 7373);
    EXPECT_EQ(colmap_step_options(fast, 320, 240).max_num_features, 2458);  // doubled for SIFT
    ColmapSettings balanced;
    balanced.quality = PosesQuality::Balanced;
    EXPECT_EQ(colmap_step_options(balanced, 540, 960).max_num_features, 4147);
    // A small frame doubled for SIFT keeps at least 1024 whatever its budget per megapixel: shrunk to 160x120
    // and doubled, 8000 per megapixel would be 614.
    fast.max_image_size = 160;
    EXPECT_EQ(colmap_step_options(fast, 320, 240).max_num_features, 1024);
}

TEST(ColmapRunner, FastKeepsOneOrientationAndMatchesFewerNeighbours) {
    ColmapSettings s;  // fast
    EXPECT_EQ(value_of(colmap_step_options(s, 540, 960).extraction, "--SiftExtraction.max_num_orientations"),
              "1");
    EXPECT_EQ(sequential_overlap_of(s), 5);
    // A frame small enough to be doubled has few features: it keeps them all.
    EXPECT_EQ(value_of(colmap_step_options(s, 320, 240).extraction, "--SiftExtraction.max_num_orientations"),
              "2");
    s.quality = PosesQuality::Balanced;
    EXPECT_EQ(value_of(colmap_step_options(s, 540, 960).extraction, "--SiftExtraction.max_num_orientations"),
              "2");  // COLMAP's
    EXPECT_EQ(sequential_overlap_of(s), 15);
    s.quality = PosesQuality::Best;
    EXPECT_FALSE(
        mentions(colmap_step_options(s, 540, 960).extraction, "--SiftExtraction.max_num_orientations"));
    EXPECT_EQ(sequential_overlap_of(s), 15);
    s.sequential_overlap = 8;  // an explicit overlap wins over the quality's
    EXPECT_EQ(sequential_overlap_of(s), 8);
    s.quality = PosesQuality::Fast;
    EXPECT_EQ(sequential_overlap_of(s), 8);
}

TEST(ColmapRunner, FastDoublesOnlySmallFrames) {
    ColmapSettings fast;
    EXPECT_EQ(fast.quality, PosesQuality::Fast);  // the default
    EXPECT_EQ(value_of(colmap_step_options(fast, 540, 960).extraction, "--SiftExtraction.first_octave"), "0");
    EXPECT_EQ(value_of(colmap_step_options(fast, 720, 1280).extraction, "--SiftExtraction.first_octave"),
              "0");
    // 320x240 without doubling registered a third fewer frames (docs/benchmarks.md).
    EXPECT_EQ(value_of(colmap_step_options(fast, 320, 240).extraction, "--SiftExtraction.first_octave"),
              "-1");
    // A 4K frame shrunk to --max-image-size 600 is a small frame again.
    fast.max_image_size = 600;
    EXPECT_EQ(value_of(colmap_step_options(fast, 2160, 3840).extraction, "--SiftExtraction.first_octave"),
              "-1");
    ColmapSettings balanced;
    balanced.quality = PosesQuality::Balanced;
    EXPECT_EQ(value_of(colmap_step_options(balanced, 720, 1280).extraction, "--SiftExtraction.first_octave"),
              "-1");
}

}  // namespace
}  // namespace npt::capture
