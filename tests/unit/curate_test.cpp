// The curate stage on synthetic frames made here: blur score, window/threshold selection, subject mask and
// centroid rule, settings errors; and one run of the whole stage on a tiny ffmpeg-made video.
#include "capture/curate.h"
#include "core/executable.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>

#include "test_support.h"

namespace npt::capture {
namespace {

Frame8 make_frame(int w, int h, uint8_t r, uint8_t g, uint8_t b) {
    Frame8 f;
    f.width = w;
    f.height = h;
    f.rgb.resize(size_t(w) * size_t(h) * 3);
    for (size_t i = 0; i < f.rgb.size(); i += 3) {
        f.rgb[i] = r;
        f.rgb[i + 1] = g;
        f.rgb[i + 2] = b;
    }
    return f;
}

void set_px(Frame8& f, int x, int y, uint8_t r, uint8_t g, uint8_t b) {
    uint8_t* p = &f.rgb[(size_t(y) * size_t(f.width) + size_t(x)) * 3];
    p[0] = r;
    p[1] = g;
    p[2] = b;
}

// A green disc (hue 120) on a grey background; pixel centres at +0.5, so the disc is symmetric about (cx,
// cy).
Frame8 disc_frame(int w, int h, float cx, float cy, float radius) {
    Frame8 f = make_frame(w, h, 128, 128, 128);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const float dx = x + 0.5f - cx, dy = y + 0.5f - cy;
            if (dx * dx + dy * dy <= radius * radius) set_px(f, x, y, 20, 220, 20);
        }
    }
    return f;
}

HsvRange green_range() {
    HsvRange r;
    r.h_min = 100;
    r.h_max = 140;
    r.s_min = 0.5f;
    r.s_max = 1.0f;
    r.v_min = 0.5f;
    r.v_max = 1.0f;
    return r;
}

Frame8 checkerboard(int w, int h, int cell) {
    Frame8 f = make_frame(w, h, 0, 0, 0);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const uint8_t v = ((x / cell + y / cell) % 2) ? 230 : 25;
            set_px(f, x, y, v, v, v);
        }
    }
    return f;
}

Frame8 box_blur(const Frame8& in, int radius) {
    Frame8 out = in;
    for (int y = 0; y < in.height; ++y) {
        for (int x = 0; x < in.width; ++x) {
            for (int c = 0; c < 3; ++c) {
                int sum = 0, n = 0;
                for (int dy = -radius; dy <= radius; ++dy) {
                    for (int dx = -radius; dx <= radius; ++dx) {
                        const int xx = std::clamp(x + dx, 0, in.width - 1),
                                  yy = std::clamp(y + dy, 0, in.height - 1);
                        sum += in.at(xx, yy)[c];
                        ++n;
                    }
                }
                out.rgb[(size_t(y) * size_t(in.width) + size_t(x)) * 3 + size_t(c)] = uint8_t(sum / n);
            }
        }
    }
    return out;
}

TEST(Curate, LaplacianVarianceOrdersSharpAboveBlurred) {
    const Frame8 sharp = checkerboard(96, 64, 8);
    const Frame8 soft = box_blur(sharp, 1);
    const Frame8 softer = box_blur(sharp, 3);
    const double s0 = laplacian_variance(to_grey(sharp, 0));
    const double s1 = laplacian_variance(to_grey(soft, 0));
    const double s2 = laplacian_variance(to_grey(softer, 0));
    EXPECT_GT(s0, s1);
    EXPECT_GT(s1, s2);
    EXPECT_GT(s2, 0.0);
    // A flat image has no edges at all.
    EXPECT_EQ(laplacian_variance(to_grey(make_frame(32, 32, 90, 90, 90), 0)), 0.0);
    // Downscaling for speed keeps the order.
    EXPECT_GT(laplacian_variance(to_grey(sharp, 48)), laplacian_variance(to_grey(softer, 48)));
}

TEST(Curate, ToGreyDownscalesToTheLongestSide) {
    const Grey g = to_grey(make_frame(1280, 720, 255, 255, 255), 480);
    EXPECT_LE(std::max(g.width, g.height), 480);
    EXPECT_NEAR(g.at(0, 0), 255.0f, 1e-3f);
}

TEST(Curate, WindowRulePicksTheSharpestPerWindowAndDropsABlurredWindow) {
    // 10 windows of 2 frames; window 3 (frames 6, 7) is blurred throughout.
    std::vector<double> scores = {100, 110, 120, 90,  95,  105, 1,   2,   100, 101,
                                  99,  98,  97,  130, 100, 100, 100, 100, 104, 103};
    const std::vector<bool> all(scores.size(), true);
    const Selection s = select_sharp(scores, all, SharpnessRule::Window, 10);
    const std::vector<size_t> expect_kept = {1, 2, 5, 9, 10, 13, 14, 16, 18};  // ties: the earlier frame
    std::vector<size_t> kept;
    for (size_t i = 0; i < scores.size(); ++i) {
        if (s.kept[i]) kept.push_back(i);
    }
    EXPECT_EQ(kept, expect_kept);
    EXPECT_NE(s.reason[7].find("blurry"), std::string::npos) << s.reason[7];
    EXPECT_NE(s.reason[0].find("not the sharpest"), std::string::npos) << s.reason[0];
    // A frame that is no candidate (dropped by the subject rule) is never chosen: its window's next best is.
    std::vector<bool> some = all;
    some[1] = false;
    EXPECT_TRUE(select_sharp(scores, some, SharpnessRule::Window, 10).kept[0]);
}

TEST(Curate, ThresholdRuleKeepsFramesAboveMeanMinusOneSigma) {
    const std::vector<double> scores = {10, 10, 10, 10, 0};  // mean 8, sigma 4: cut at 4
    const Selection s = select_sharp(scores, std::vector<bool>(5, true), SharpnessRule::Threshold, 1);
    EXPECT_EQ(s.kept, (std::vector<bool>{true, true, true, true, false}));
    EXPECT_NEAR(s.mean, 8.0, 1e-12);
    EXPECT_NEAR(s.stddev, 4.0, 1e-12);
}

TEST(Curate, MaskCentroidOfAKnownDisc) {
    const Frame8 f = disc_frame(120, 80, 40.0f, 25.0f, 10.0f);
    const MaskResult m = subject_centroid(f, green_range(), 0);
    ASSERT_TRUE(m.centroid.has_value());
    EXPECT_NEAR(m.centroid->x, 40.0f, 1e-3f);
    EXPECT_NEAR(m.centroid->y, 25.0f, 1e-3f);
    // On a copy downscaled by 4 the centroid moves by less than one block.
    const Frame8 big = disc_frame(480, 320, 160.0f, 100.0f, 40.0f);
    const MaskResult d = subject_centroid(big, green_range(), 120);
    ASSERT_TRUE(d.centroid.has_value());
    EXPECT_NEAR(d.centroid->x, 160.0f, 2.0f);
    EXPECT_NEAR(d.centroid->y, 100.0f, 2.0f);
    // A smaller second blob does not move the centroid: only the largest component counts.
    Frame8 two = f;
    for (int y = 70; y < 74; ++y)
        for (int x = 100; x < 104; ++x) set_px(two, x, y, 20, 220, 20);
    EXPECT_NEAR(subject_centroid(two, green_range(), 0).centroid->x, 40.0f, 1e-3f);
    EXPECT_FALSE(subject_centroid(make_frame(16, 16, 128, 128, 128), green_range(), 0).centroid.has_value());
}

TEST(Curate, AutomaticRangeFindsTheCentredSubject) {
    const Frame8 f = disc_frame(120, 80, 60.0f, 40.0f, 20.0f);
    const HsvRange r = automatic_range(f);
    EXPECT_TRUE(r.contains(120.0f, 0.9f, 0.86f));
    EXPECT_FALSE(r.contains(0.0f, 0.0f, 0.5f));  // the grey background
    const MaskResult m = subject_centroid(f, r, 0);
    ASSERT_TRUE(m.centroid.has_value());
    EXPECT_NEAR(m.centroid->x, 60.0f, 1e-3f);
}

TEST(Curate, CentroidRuleDropsOffCentreFramesAndKeepsCentredOnes) {
    CurateReport report;
    CurateSettings settings;
    const int w = 160, h = 120;
    for (int i = 0; i < 12; ++i) {
        // Frames 4 and 9: the camera looked away, the disc is near a corner. The others jitter by a pixel.
        const bool away = i == 4 || i == 9;
        const float cx = away ? 130.0f : 80.0f + float(i % 3) - 1.0f;
        const float cy = away ? 95.0f : 60.0f + float(i % 2);
        const Frame8 f = disc_frame(w, h, cx, cy, 12.0f);
        FrameRecord rec;
        rec.index = i;
        rec.sharpness = 100.0;
        rec.centroid = subject_centroid(f, green_range(), 0).centroid;
        report.frames.push_back(rec);
    }
    apply_rules(report, settings, w);
    for (int i = 0; i < 12; ++i) {
        const FrameRecord& f = report.frames[size_t(i)];
        if (i == 4 || i == 9) {
            EXPECT_FALSE(f.kept) << i;
            EXPECT_NE(f.reason.find("subject off-centre"), std::string::npos) << f.reason;
        } else {
            EXPECT_TRUE(f.kept) << i << ": " << f.reason;
        }
    }
    EXPECT_EQ(report.kept, 10);
}

TEST(Curate, BadSettingsAreOneLineErrors) {
    CurateSettings s;
    s.target_frames = 0;
    test::expect_error_message([&] { validate_settings(s); }, {"--target-frames", "0"});
    s = CurateSettings{};
    HsvRange r = green_range();
    r.s_min = 0.9f;
    r.s_max = 0.2f;
    s.hsv = r;
    test::expect_error_message([&] { validate_settings(s); }, {"--hsv-min", "S"});
    r = green_range();
    r.h_max = 400.0f;
    s.hsv = r;
    test::expect_error_message([&] { validate_settings(s); }, {"H", "360"});
    s = CurateSettings{};
    s.max_frames = -1;
    test::expect_error_message([&] { validate_settings(s); }, {"--max-frames"});
}

TEST(Curate, ContactSheetFramesKeptGreenAndDroppedRed) {
    const std::vector<Frame8> thumbs = {make_frame(10, 6, 0, 0, 255), make_frame(10, 6, 0, 0, 255)};
    const Frame8 sheet = contact_sheet(thumbs, {true, false});
    ASSERT_GT(sheet.width, 20);
    // Top-left corner of the first cell's border is green, of the second red (cells side by side or stacked).
    const uint8_t* first = sheet.at(2, 2);
    EXPECT_GT(first[1], 150);
    EXPECT_LT(first[0], 100);
}

bool have_ffmpeg() { return !find_executable("ffmpeg").empty() && !find_executable("ffprobe").empty(); }

TEST(Curate, WholeStageOnATinyVideo) {
    if (!have_ffmpeg()) GTEST_SKIP() << "ffmpeg/ffprobe not on PATH: the curate end-to-end test needs them";
    const std::filesystem::path dir = test::temp_dir();
    const std::filesystem::path video = dir / "tiny.mp4";
    const std::string make =
        "ffmpeg -nostdin -v error -y -f lavfi -i testsrc=size=64x48:rate=10 -t 2 -pix_fmt yuv420p " +
        shell_quote(video.string());
    ASSERT_EQ(std::system(make.c_str()), 0);
    const VideoInfo info = probe_video(video);
    EXPECT_EQ(info.width, 64);
    EXPECT_EQ(info.height, 48);
    EXPECT_EQ(info.frame_count, 20);

    CurateSettings s;
    s.target_frames = 5;
    s.max_frames = 10;  // every second frame: 0, 2, ..., 18
    const std::filesystem::path out = dir / "frames";
    std::filesystem::create_directories(out);
    test::write_file(out / "frame_99999.png", "stale");  // from an "earlier run": must go
    const CurateReport r = curate_video(video, out, s);
    ASSERT_EQ(r.frames.size(), 10u);
    EXPECT_EQ(r.frames[3].index, 6);
    EXPECT_NEAR(r.frames[3].time, 0.6, 1e-9);
    EXPECT_GE(r.kept, 1);
    EXPECT_LE(r.kept, 5);
    int pngs = 0;
    for (const auto& e : std::filesystem::directory_iterator(out)) {
        const std::string name = e.path().filename().string();
        if (name.rfind("frame_", 0) == 0) ++pngs;
    }
    EXPECT_EQ(pngs, r.kept);
    EXPECT_FALSE(std::filesystem::exists(out / "frame_99999.png"));
    EXPECT_TRUE(std::filesystem::exists(out / "contact_sheet.png"));
    std::ifstream in(out / "curate.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j["totals"]["decoded"], 10);
    EXPECT_EQ(j["totals"]["kept"], r.kept);
    EXPECT_EQ(j["frames"].size(), 10u);
    for (const auto& f : j["frames"]) {
        if (f["kept"].get<bool>()) {
            EXPECT_TRUE(std::filesystem::exists(out / f["file"].get<std::string>()));
        } else {
            EXPECT_FALSE(f["reason"].get<std::string>().empty());
        }
    }
}

TEST(Curate, PhoneRotationMetadataGivesUprightFrames) {
    if (!have_ffmpeg()) GTEST_SKIP() << "ffmpeg/ffprobe not on PATH: the rotation test needs them";
    const std::filesystem::path dir = test::temp_dir();
    const std::filesystem::path plain = dir / "plain.mp4", rotated = dir / "rotated.mp4";
    const std::string make =
        "ffmpeg -nostdin -v error -y -f lavfi -i testsrc=size=64x48:rate=10 -t 1 -pix_fmt yuv420p " +
        shell_quote(plain.string()) + " && ffmpeg -nostdin -v error -y -i " + shell_quote(plain.string()) +
        " -c copy -metadata:s:v:0 rotate=90 " + shell_quote(rotated.string());
    ASSERT_EQ(std::system(make.c_str()), 0);
    // A phone stores landscape sensor frames plus a quarter-turn; ffmpeg autorotates, so the frames are
    // 48x64.
    const VideoInfo info = probe_video(rotated);
    EXPECT_EQ(info.width, 48);
    EXPECT_EQ(info.height, 64);
    FrameReader reader(rotated, info, 1, 3);
    Frame8 f;
    int n = 0;
    while (reader.next(f)) ++n;  // a size mismatch would be a truncated-frame error
    EXPECT_EQ(n, 3);
}

// Restores $PATH however the test ends.
struct PathGuard {
    std::string saved;
    explicit PathGuard(const std::filesystem::path& replacement) {
        const char* old = std::getenv("PATH");
        saved = old ? old : "";
        ::setenv("PATH", replacement.c_str(), 1);
    }
    ~PathGuard() { ::setenv("PATH", saved.c_str(), 1); }
};

TEST(Curate, MissingFfmpegIsAOneLineError) {
    const std::filesystem::path dir = test::temp_dir();
    test::write_file(dir / "clip.mp4", "x");
    const PathGuard guard(dir);  // a folder with no ffmpeg in it
    test::expect_error_message([&] { probe_video(dir / "clip.mp4"); }, {"clip.mp4", "ffmpeg", "PATH"});
}

TEST(Curate, NotAVideoAndMissingFileAreOneLineErrors) {
    if (!have_ffmpeg()) GTEST_SKIP() << "ffmpeg/ffprobe not on PATH: needed to probe the file";
    const std::filesystem::path dir = test::temp_dir();
    test::write_file(dir / "notes.mp4", "this is not a video\n");
    test::expect_error_message([&] { probe_video(dir / "notes.mp4"); }, {"notes.mp4", "not a video"});
    test::expect_error_message([&] { probe_video(dir / "missing.mp4"); }, {"missing.mp4", "no such file"});
}

}  // namespace
}  // namespace npt::capture
