#include "capture/curate.h"

#include <fmt/format.h>
#include <stb_image_write.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <regex>

#include "core/error.h"
#include "core/temp_file.h"

namespace npt::capture {

void validate_settings(const CurateSettings& s) {
    if (s.target_frames <= 0) {
        throw Error(fmt::format("curate: --target-frames must be at least 1 (got {})", s.target_frames));
    }
    if (s.max_frames < 0)
        throw Error(fmt::format("curate: --max-frames must be >= 0 (got {})", s.max_frames));
    if (s.hsv) validate_range(*s.hsv);
    if (s.analysis_side < 16) throw Error("curate: analysis size must be at least 16 pixels");
    if (s.thumb_side < 8) throw Error("curate: thumbnail size must be at least 8 pixels");
}

void apply_rules(CurateReport& report, const CurateSettings& settings, int frame_side) {
    std::vector<std::optional<Vec2>> centroids;
    std::vector<double> scores;
    for (const FrameRecord& f : report.frames) {
        centroids.push_back(f.centroid);
        scores.push_back(f.sharpness);
    }
    const std::vector<std::string> off =
        centroid_outliers(centroids, 0.01 * frame_side, report.centroid_centre, report.centroid_sigma);
    std::vector<bool> candidate(off.size());
    for (size_t i = 0; i < off.size(); ++i) candidate[i] = off[i].empty();
    report.sharp = select_sharp(scores, candidate, settings.rule, settings.target_frames);
    report.kept = 0;
    for (size_t i = 0; i < report.frames.size(); ++i) {
        FrameRecord& f = report.frames[i];
        f.kept = candidate[i] && report.sharp.kept[i];
        f.reason = !candidate[i] ? off[i] : report.sharp.reason[i];
        report.kept += f.kept ? 1 : 0;
    }
}

Frame8 thumbnail(const Frame8& frame, int side) {
    const int longest = std::max(frame.width, frame.height);
    const int f = longest > side ? (longest + side - 1) / side : 1;
    Frame8 t;
    t.width = std::max(1, frame.width / f);
    t.height = std::max(1, frame.height / f);
    t.rgb.assign(size_t(t.width) * size_t(t.height) * 3, 0);
    for (int y = 0; y < t.height; ++y) {
        for (int x = 0; x < t.width; ++x) {
            int sum[3] = {0, 0, 0};
            for (int dy = 0; dy < f; ++dy) {
                for (int dx = 0; dx < f; ++dx) {
                    const uint8_t* p = frame.at(std::min(frame.width - 1, x * f + dx),
                                                std::min(frame.height - 1, y * f + dy));
                    for (int c = 0; c < 3; ++c) sum[c] += p[c];
                }
            }
            for (int c = 0; c < 3; ++c) {
                t.rgb[(size_t(y) * size_t(t.width) + size_t(x)) * 3 + size_t(c)] = uint8_t(sum[c] / (f * f));
            }
        }
    }
    return t;
}

Frame8 contact_sheet(const std::vector<Frame8>& thumbs, const std::vector<bool>& kept) {
    constexpr int k_border = 3, k_gap = 2;
    Frame8 sheet;
    if (thumbs.empty()) return sheet;
    int tw = 0, th = 0;
    for (const Frame8& t : thumbs) {
        tw = std::max(tw, t.width);
        th = std::max(th, t.height);
    }
    const int cw = tw + 2 * k_border + k_gap, ch = th + 2 * k_border + k_gap;
    // Roughly square sheet whatever the thumbnails' aspect.
    const int cols = std::max(1, int(std::ceil(std::sqrt(double(thumbs.size()) * ch / cw))));
    const int rows = int((thumbs.size() + size_t(cols) - 1) / size_t(cols));
    sheet.width = cols * cw + k_gap;
    sheet.height = rows * ch + k_gap;
    sheet.rgb.assign(size_t(sheet.width) * size_t(sheet.height) * 3, 32);
    for (size_t i = 0; i < thumbs.size(); ++i) {
        const Frame8& t = thumbs[i];
        const int ox = k_gap + int(i % size_t(cols)) * cw, oy = k_gap + int(i / size_t(cols)) * ch;
        const uint8_t colour[3] = {uint8_t(kept[i] ? 40 : 220), uint8_t(kept[i] ? 200 : 40), 40};
        for (int y = 0; y < t.height + 2 * k_border; ++y) {
            for (int x = 0; x < t.width + 2 * k_border; ++x) {
                uint8_t* d = &sheet.rgb[(size_t(oy + y) * size_t(sheet.width) + size_t(ox + x)) * 3];
                const bool inside =
                    x >= k_border && y >= k_border && x < t.width + k_border && y < t.height + k_border;
                const uint8_t* s = inside ? t.at(x - k_border, y - k_border) : colour;
                std::copy(s, s + 3, d);
            }
        }
    }
    return sheet;
}

void write_rgb8_png(const std::filesystem::path& path, const Frame8& frame) {
    if (!stbi_write_png(path.string().c_str(), frame.width, frame.height, 3, frame.rgb.data(),
                        frame.width * 3)) {
        throw Error(fmt::format("{}: could not write the PNG", path.string()));
    }
}

void write_curate_json(const std::filesystem::path& path, const std::filesystem::path& video,
                       const CurateReport& r, const CurateSettings& s) {
    using nlohmann::json;
    json frames = json::array();
    int dropped_subject = 0, dropped_sharpness = 0;
    for (const FrameRecord& f : r.frames) {
        json j = {{"index", f.index}, {"time", f.time}, {"sharpness", f.sharpness}, {"kept", f.kept}};
        j["centroid"] = f.centroid ? json::array({f.centroid->x, f.centroid->y}) : json(nullptr);
        if (f.kept) {
            j["file"] = fmt::format("frame_{:05d}.png", f.index);
        } else {
            j["reason"] = f.reason;
            const bool subject = f.reason.rfind("subject", 0) == 0 || f.reason.rfind("no subject", 0) == 0;
            (subject ? dropped_subject : dropped_sharpness) += 1;
        }
        frames.push_back(std::move(j));
    }
    json doc = {{"video", video.string()},
                {"video_info",
                 {{"width", r.info.width},
                  {"height", r.info.height},
                  {"fps", r.info.fps},
                  {"frame_count", r.info.frame_count}}},
                {"settings",
                 {{"rule", s.rule == SharpnessRule::Window ? "window" : "threshold"},
                  {"target_frames", s.target_frames},
                  {"max_frames", s.max_frames},
                  {"analysis_side", s.analysis_side},
                  {"hsv_automatic", r.hsv_automatic},
                  {"hsv_min", {r.hsv.h_min, r.hsv.s_min, r.hsv.v_min}},
                  {"hsv_max", {r.hsv.h_max, r.hsv.s_max, r.hsv.v_max}},
                  {"centroid_sigmas", k_centroid_sigmas}}},
                {"sharpness", {{"mean", r.sharp.mean}, {"stddev", r.sharp.stddev}}},
                {"centroid",
                 {{"centre", {r.centroid_centre.x, r.centroid_centre.y}},
                  {"sigma", {r.centroid_sigma.x, r.centroid_sigma.y}}}},
                {"totals",
                 {{"decoded", r.frames.size()},
                  {"kept", r.kept},
                  {"dropped_subject", dropped_subject},
                  {"dropped_sharpness", dropped_sharpness}}},
                {"seconds", r.seconds},
                {"frames", frames}};
    write_text_atomic(path, doc.dump(2) + "\n");
}

CurateReport curate_video(const std::filesystem::path& video, const std::filesystem::path& out_dir,
                          const CurateSettings& settings, const ProgressFn& on_decode,
                          const ProgressFn& on_write) {
    validate_settings(settings);
    const auto t0 = std::chrono::steady_clock::now();
    CurateReport report;
    report.info = probe_video(video);
    const int64_t total = report.info.frame_count;
    const int64_t wanted = settings.max_frames > 0 ? std::min(settings.max_frames, total) : total;
    const int64_t step = (total + wanted - 1) / wanted;

    std::error_code ec;
    std::filesystem::create_directories(out_dir, ec);
    if (ec)
        throw Error(
            fmt::format("{}: could not create the output folder ({})", out_dir.string(), ec.message()));

    std::vector<Frame8> thumbs;
    {
        FrameReader reader(video, report.info, step, wanted);
        Frame8 frame;
        while (reader.next(frame)) {
            if (report.frames.empty()) {
                report.hsv_automatic = !settings.hsv;
                // The first frame: filming starts with the object in view and centred.
                report.hsv = settings.hsv ? *settings.hsv : automatic_range(frame);
            }
            FrameRecord rec;
            rec.index = reader.source_index();
            rec.time = double(rec.index) / report.info.fps;
            rec.sharpness = laplacian_variance(to_grey(frame, settings.analysis_side));
            rec.centroid = subject_centroid(frame, report.hsv, settings.analysis_side).centroid;
            report.frames.push_back(rec);
            thumbs.push_back(thumbnail(frame, settings.thumb_side));
            if (on_decode) on_decode(uint64_t(report.frames.size()), uint64_t(wanted));
        }
    }
    if (report.frames.empty()) throw Error(fmt::format("{}: ffmpeg decoded zero frames", video.string()));
    apply_rules(report, settings, std::max(report.info.width, report.info.height));

    // Remove frames of an earlier run first, so that the folder holds exactly this run's selection.
    const std::regex frame_name(R"(frame_\d+\.png)");
    for (const auto& entry : std::filesystem::directory_iterator(out_dir)) {
        if (entry.is_regular_file() && std::regex_match(entry.path().filename().string(), frame_name)) {
            std::filesystem::remove(entry.path());
        }
    }
    {
        FrameReader reader(video, report.info, step, wanted);
        Frame8 frame;
        size_t i = 0;
        int written = 0;
        while (written < report.kept && reader.next(frame) && i < report.frames.size()) {
            if (report.frames[i].kept) {
                write_rgb8_png(out_dir / fmt::format("frame_{:05d}.png", report.frames[i].index), frame);
                ++written;
                if (on_write) on_write(uint64_t(written), uint64_t(report.kept));
            }
            ++i;
        }
        // The second decode must give the frames the first one scored; a short one would leave curate.json
        // naming files that were never written.
        if (written != report.kept)
            throw Error(fmt::format("{}: ffmpeg returned fewer frames the second time ({} of {} kept frames "
                                    "written); the file may be damaged",
                                    video.string(), written, report.kept));
    }
    std::vector<bool> kept;
    for (const FrameRecord& f : report.frames) kept.push_back(f.kept);
    write_rgb8_png(out_dir / "contact_sheet.png", contact_sheet(thumbs, kept));
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    write_curate_json(out_dir / "curate.json", video, report, settings);
    return report;
}

}  // namespace npt::capture
