// Splitting a shot for farms: frame ranges, contiguous task chunks whose union is the shot (each frame once),
// SLURM's variables, frame file names and per-frame seeds.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "core/error.h"
#include "dist/frames.h"
#include "test_support.h"

namespace npt::dist {
namespace {

TEST(Frames, ParsesRanges) {
    EXPECT_EQ(parse_frame_range("1-5").frames(), (std::vector<int>{1, 2, 3, 4, 5}));
    EXPECT_EQ(parse_frame_range("1-10:4").frames(), (std::vector<int>{1, 5, 9}));
    EXPECT_EQ(parse_frame_range("7").frames(), (std::vector<int>{7}));
    EXPECT_EQ(parse_frame_range("0-0").frames(), (std::vector<int>{0}));
    for (const char* bad : {"", "5-1", "a-3", "1-", "-3", "1-3:0", "1-3:x", "1-99999999", "1--3"})
        test::expect_error_message([&] { parse_frame_range(bad); }, {"--frames", std::string("'") + bad + "'"});
}

TEST(Frames, TasksCoverTheShotExactlyOnceInContiguousChunks) {
    for (int n_frames : {1, 7, 48, 240})
        for (int step : {1, 3})
            for (int count : {1, 2, 3, 5, 8, 300}) {
                const std::vector<int> shot = FrameRange{1, n_frames, step}.frames();
                std::vector<int> joined;
                size_t smallest = shot.size(), largest = 0;
                for (int i = 0; i < count; ++i) {
                    const std::vector<int> mine = task_frames(shot, i, count);
                    joined.insert(joined.end(), mine.begin(), mine.end());
                    smallest = std::min(smallest, mine.size());
                    largest = std::max(largest, mine.size());
                }
                // In task order the chunks concatenate to the shot: every frame once, in order, chunks contiguous.
                EXPECT_EQ(joined, shot) << n_frames << " frames, step " << step << ", " << count << " tasks";
                EXPECT_LE(largest - smallest, 1u);
            }
    EXPECT_THROW(task_frames({1, 2}, 2, 2), Error);
}

std::map<std::string, std::string> g_env;
const char* fake_getenv(const char* name) {
    auto it = g_env.find(name);
    return it == g_env.end() ? nullptr : it->second.c_str();
}

TEST(Frames, TaskFromOptionsOrSlurm) {
    g_env.clear();
    TaskSlot t = resolve_task(std::nullopt, std::nullopt, fake_getenv);
    EXPECT_EQ(t.index, 0);
    EXPECT_EQ(t.count, 1);
    g_env = {{"SLURM_ARRAY_TASK_ID", "3"}, {"SLURM_ARRAY_TASK_COUNT", "4"}};
    t = resolve_task(std::nullopt, std::nullopt, fake_getenv);
    EXPECT_EQ(t.index, 3);
    EXPECT_EQ(t.count, 4);
    g_env["SLURM_ARRAY_TASK_MIN"] = "1";  // --array=1-4
    t = resolve_task(std::nullopt, std::nullopt, fake_getenv);
    EXPECT_EQ(t.index, 2);
    t = resolve_task(1, 2, fake_getenv);  // options win
    EXPECT_EQ(t.index, 1);
    EXPECT_EQ(t.count, 2);
    test::expect_error_message([] { resolve_task(2, 2, fake_getenv); }, {"--task-index", "0..1"});
    test::expect_error_message([] { resolve_task(1, std::nullopt, fake_getenv); }, {"--task-count"});
    g_env = {{"SLURM_ARRAY_TASK_ID", "4"}, {"SLURM_ARRAY_TASK_COUNT", "4"}};
    test::expect_error_message([] { resolve_task(std::nullopt, std::nullopt, fake_getenv); }, {"SLURM_ARRAY_TASK_ID=4"});
    g_env = {{"SLURM_ARRAY_TASK_ID", "x"}, {"SLURM_ARRAY_TASK_COUNT", "4"}};
    test::expect_error_message([] { resolve_task(std::nullopt, std::nullopt, fake_getenv); }, {"SLURM_ARRAY_TASK_ID='x'"});
    g_env.clear();
}

TEST(Frames, FramePaths) {
    EXPECT_EQ(frame_path("out/shot.####.exr", 7), std::filesystem::path("out/shot.0007.exr"));
    EXPECT_EQ(frame_path("a#b.##.exr", 123), std::filesystem::path("a#b.123.exr"));  // the last run, widened
    EXPECT_EQ(frame_path("f#.exr", 3), std::filesystem::path("f3.exr"));
    test::expect_error_message([] { frame_path("shot.exr", 1); }, {"shot.exr", "####"});
}

TEST(Frames, FrameSeedsDifferAndRepeat) {
    std::set<uint64_t> seeds;
    for (int f = 0; f < 1000; ++f) seeds.insert(frame_seed(0, f));
    EXPECT_EQ(seeds.size(), 1000u);
    EXPECT_EQ(frame_seed(5, 12), frame_seed(5, 12));
    EXPECT_NE(frame_seed(5, 12), frame_seed(6, 12));
}

}  // namespace
}  // namespace npt::dist
