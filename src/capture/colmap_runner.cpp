#include "capture/colmap_runner.h"


#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <thread>
#include <vector>

#include "capture/pose_alignment.h"
#include "capture/revisit_pairs.h"
#include "core/error.h"
#include "core/executable.h"
#include "core/image_io.h"

namespace npt::capture {
namespace fs = std::filesystem;

namespace {

std::string last_line_of(const fs::path& file) {
    std::ifstream in(file);
    std::string line, last;
    while (std::getline(in, line))
        if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
    return last.empty() ? "no output" : last;
}

// Frames are the folder's images, except the contact sheet `nerfpt curate` writes beside them.
bool is_image(const fs::path& p) {
    if (p.filename() == "contact_sheet.png") return false;
    std::string ext = p.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

// What a quality changes from COLMAP's defaults; the numbers are measured in docs/benchmarks.md ("How fast
// COLMAP can be"). The CPU matcher of COLMAP 3.8 (FLANN k-d trees, built and searched per pair) costs about
// 0.08-0.09 ms per feature per pair (the synthetic 540x960 capture: 825, 1557 and 2440 features per frame,
// 84, 189 and 285 CPU seconds for 1295 pairs), so matching grows with features x pairs; extraction with the
// pixels SIFT runs on (doubling the frame: 4x) and the features it keeps; mapping mostly with how often the
// global bundle adjustment runs.
struct QualityPreset {
    bool colmap_defaults;  // best: pass nothing but the threads and max_image_size
    // SIFT on the frame doubled (COLMAP's first_octave -1, 4x the pixels) or at its own size (0). Doubling
    // finds the small features that a frame smaller than k_min_sift_side needs to register at all.
    bool upsample;
    // Feature budget per frame (COLMAP's max_num_features): this many per megapixel of the frame SIFT sees,
    // within [min, max]. COLMAP keeps whole scale levels, coarsest first, until the budget is passed, so a
    // frame keeps up to ~1.6x the budget (540x960, budget 518: 825 features per frame; budget 4147: every
    // scale, ~2500 features with one orientation each).
    double features_per_megapixel;
    int min_features, max_features;
    // Orientations SIFT may give one keypoint (COLMAP: 2, a second descriptor where the gradient histogram
    // has a second peak). One gave the same poses with 28% fewer 3D points and a 30% faster mapper on a
    // 100-frame handheld capture (docs/benchmarks.md, "Every scale, fewer pairs").
    int max_orientations;
    // The sequential matcher's overlap: each frame is matched with the next this many.
    int sequential_overlap;
    // Mapper: a global bundle adjustment each time the model grew by this ratio (COLMAP: 1.1), with at most
    // these iterations and refinements; local ones with at most these iterations.
    double ba_global_ratio;
    int ba_global_max_iterations, ba_global_max_refinements, ba_local_max_iterations;
    // Mapper: observations that reproject farther (px) are dropped after each adjustment (COLMAP: 4). At 2
    // the rotation error fell on all four handheld captures measured, by 2-40% (docs/benchmarks.md, "Refining
    // the model").
    double filter_max_reproj_error;
};

// Frames whose longer side is below this are doubled for SIFT even by `fast`: at 320x240 without doubling
// (~250 features) COLMAP registered 46 of 71 turntable frames, doubled (~700) all 71.
constexpr int k_min_sift_side = 800;
// A frame doubled because it is small keeps at least this budget: it has few features to begin with (the
// 320x240 turntable ~700), and the accuracy of such captures rests on all of them.
constexpr int k_min_features_doubled = 1024;
// Ceres runs a bundle adjustment single-threaded below this many residuals; COLMAP's 50000 keeps most of a
// 100-frame capture's adjustments on one core.
constexpr int k_ba_min_residuals_for_threads = 1000;

QualityPreset preset(PosesQuality q) {
    switch (q) {
        // Every scale at the frame's own size, matched with the next 5 frames: on four handheld captures the
        // rotation error's median fell by 29-65% against the coarse scales matched with the next 15, in about
        // the same time (docs/benchmarks.md, "Every scale, fewer pairs").
        case PosesQuality::Fast:
            return {false, false, 8000, 512, 8192, 1, 5, 2.0, 20, 1, 10, 2.0};
        case PosesQuality::Balanced:
            return {false, true, 2000, 2048, 8192, 2, 15, 1.5, 25, 2, 15, 2.0};
        case PosesQuality::Best:
            break;
    }
    return {true, true, 0, 8192, 8192, 2, 15, 1.1, 50, 5, 25, 4.0};
}

struct Step {
    const char* name;
    const char* log;
    std::vector<std::string> argv;
};

// Runs COLMAP step `index` (ColmapRun's arrays; a step of several commands adds up), timing it; throws naming
// the step and its log when it fails.
void run_step(int index, const Step& step, const fs::path& work, ColmapRun& run) {
    double load = 0;
    if (run.load_at_start[index] == 0 && getloadavg(&load, 1) == 1) run.load_at_start[index] = load;
    const auto t0 = std::chrono::steady_clock::now();
    const fs::path log = work / step.log;
    double cpu = 0;
    const int status = run_logged(step.argv, log, &cpu);
    run.cpu_seconds[index] += cpu;
    run.seconds[index] += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (status != 0)
        throw Error("COLMAP " + std::string(step.name) + " failed (exit " + std::to_string(status) +
                    "; log " + log.string() + "): " + last_line_of(log));
}

// The reconstruction in `sparse` (one folder per model the mapper could not join) that registered the most
// frames; false when there is none.
bool read_largest_model(const fs::path& sparse, ColmapModel& model, fs::path& folder) {
    size_t best = 0;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(sparse, ec)) {
        if (!e.is_directory() || !fs::exists(e.path() / "images.bin")) continue;
        ColmapModel m = read_colmap_model(e.path());
        if (m.images.size() > best) {
            best = m.images.size();
            model = std::move(m);
            folder = e.path();
        }
    }
    return best > 0;
}

std::string arg(double v) {
    std::string s = std::to_string(v);
    s.erase(s.find_last_not_of('0') + 1);
    if (!s.empty() && s.back() == '.') s.pop_back();
    return s;
}

// Drops the observations of run.model that reproject more than s.refine_error_ratio times its mean error and
// adjusts the whole model again, into work/sparse_refined; the refined model replaces run.model unless a step
// fails or it lost frames or its points (then run.refine_skipped says why: the poses are kept, not lost).
void refine_model(const ColmapSettings& s, const fs::path& work, ColmapRun& run,
                  const ColmapStepFn& on_step) {
    const ReprojectionStats before = reprojection_error(run.model);
    if (before.observations == 0 || !(before.mean_px > 0)) return;
    if (on_step) on_step("refinement");
    const fs::path refined = work / "sparse_refined";
    std::error_code ec;
    fs::remove_all(refined, ec);
    fs::create_directories(refined, ec);
    if (ec) throw Error(refined.string() + ": cannot create the folder (" + ec.message() + ")");
    const double threshold = s.refine_error_ratio * before.mean_px;
    ColmapModel model;
    try {
        run_step(4,
                 {"observation filtering",
                  "refine_filter.log",
                  {s.colmap, "point_filtering", "--input_path", run.model_folder.string(), "--output_path",
                   refined.string(), "--max_reproj_error", arg(threshold)}},
                 work, run);
        run_step(4,
                 {"bundle adjustment",
                  "refine_adjuster.log",
                  {s.colmap, "bundle_adjuster", "--input_path", refined.string(), "--output_path",
                   refined.string()}},
                 work, run);
        model = read_colmap_model(refined);
    } catch (const Error& e) {
        run.refine_skipped = e.what();
        return;
    }
    if (model.images.size() < run.model.images.size() || model.points.empty()) {
        run.refine_skipped = "the refined model (" + refined.string() + ") lost frames or its points";
        return;
    }
    run.refine_threshold_px = threshold;
    run.refine_error_before_px = before.mean_px;
    run.refine_error_after_px = reprojection_error(model).mean_px;
    run.model = std::move(model);
    run.model_folder = refined;
}

}  // namespace

PosesQuality parse_poses_quality(const std::string& name) {
    if (name == "fast") return PosesQuality::Fast;
    if (name == "balanced") return PosesQuality::Balanced;
    if (name == "best") return PosesQuality::Best;
    throw Error("--poses-quality '" + name + "': expected fast, balanced or best");
}

const char* poses_quality_name(PosesQuality q) {
    switch (q) {
        case PosesQuality::Fast:
            return "fast";
        case PosesQuality::Balanced:
            return "balanced";
        case PosesQuality::Best:
            break;
    }
    return "best";
}

ColmapStepOptions colmap_step_options(const ColmapSettings& s, int frame_width, int frame_height) {
    const QualityPreset p = preset(s.quality);
    const int threads = s.threads > 0 ? s.threads : std::max(1, int(std::thread::hardware_concurrency()));
    const std::string t = std::to_string(threads);
    ColmapStepOptions o;
    o.extraction = {"--SiftExtraction.num_threads", t, "--SiftExtraction.max_image_size",
                    std::to_string(s.max_image_size)};
    o.matching = {"--SiftMatching.num_threads", t};
    o.mapping = {"--Mapper.num_threads", t};
    o.max_num_features = p.max_features;
    if (p.colmap_defaults) return o;
    // The frame as SIFT sees it: shrunk to max_image_size, doubled when upsampled.
    const double side = std::max(1, std::max(frame_width, frame_height));
    const double shrink = std::min(1.0, double(s.max_image_size) / side);
    const bool upsample = p.upsample || side * shrink < k_min_sift_side;
    const double megapixels =
        double(frame_width) * double(frame_height) * shrink * shrink * (upsample ? 4.0 : 1.0) * 1e-6;
    const bool small_frame = upsample && !p.upsample;
    const int min_features = small_frame ? std::max(p.min_features, k_min_features_doubled) : p.min_features;
    // A small frame keeps COLMAP's second orientations too: it has few features, and with one the 320x240
    // turntable of the e2e test registered 69 and 63 of its 72 frames in two runs (its limit asks for 71).
    const int orientations = small_frame ? 2 : p.max_orientations;
    o.max_num_features =
        std::clamp(int(std::lround(p.features_per_megapixel * megapixels)), min_features, p.max_features);
    const std::string features = std::to_string(o.max_num_features);
    const std::vector<std::string> extraction = {
        "--SiftExtraction.first_octave",         upsample ? "-1" : "0",
        "--SiftExtraction.max_num_features",     features,
        "--SiftExtraction.max_num_orientations", std::to_string(orientations)};
    const std::vector<std::string> matching = {"--SiftMatching.max_num_matches", features};
    // Point colours are not used by nerfpt; reading every frame again for them costs ~5% of the mapping.
    // clang-format off
    const std::vector<std::string> mapping = {
        "--Mapper.ba_global_images_ratio", arg(p.ba_global_ratio),
        "--Mapper.ba_global_points_ratio", arg(p.ba_global_ratio),
        "--Mapper.ba_global_max_num_iterations", std::to_string(p.ba_global_max_iterations),
        "--Mapper.ba_global_max_refinements", std::to_string(p.ba_global_max_refinements),
        "--Mapper.ba_local_max_num_iterations", std::to_string(p.ba_local_max_iterations),
        "--Mapper.ba_min_num_residuals_for_multi_threading", std::to_string(k_ba_min_residuals_for_threads),
        "--Mapper.filter_max_reproj_error", arg(p.filter_max_reproj_error),
        "--Mapper.extract_colors", "0"};
    // clang-format on
    o.extraction.insert(o.extraction.end(), extraction.begin(), extraction.end());
    o.matching.insert(o.matching.end(), matching.begin(), matching.end());
    o.mapping.insert(o.mapping.end(), mapping.begin(), mapping.end());
    return o;
}

int sequential_overlap_of(const ColmapSettings& s) {
    return s.sequential_overlap > 0 ? s.sequential_overlap : preset(s.quality).sequential_overlap;
}

std::vector<std::string> list_frames(const fs::path& frames) {
    std::vector<std::string> names;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(frames, ec))
        if (e.is_regular_file() && is_image(e.path())) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

size_t count_frames(const fs::path& frames) { return list_frames(frames).size(); }

ColmapRun run_colmap(const fs::path& frames, const fs::path& work, const ColmapSettings& s,
                     const ColmapStepFn& on_step) {
    if (s.matcher != "sequential" && s.matcher != "exhaustive")
        throw Error("--matcher '" + s.matcher + "': expected sequential or exhaustive");
    std::error_code ec;
    if (!fs::is_directory(frames, ec)) throw Error(frames.string() + ": not a folder of frames");
    ColmapRun run;
    const std::vector<std::string> names = list_frames(frames);
    run.frames = names.size();
    if (run.frames < 3)
        throw Error(frames.string() + ": " + std::to_string(run.frames) +
                    " images (.png/.jpg); COLMAP needs at least 3, and a good capture 50-200");
    if (find_executable(s.colmap).empty())
        throw Error("'" + s.colmap + "' not found on PATH: install COLMAP (Debian: apt-get install colmap)");
    fs::create_directories(work, ec);
    if (ec) throw Error(work.string() + ": cannot create the work folder (" + ec.message() + ")");
    const fs::path db = work / "database.db";
    fs::remove(db, ec);
    fs::remove_all(work / "sparse", ec);
    fs::remove_all(work / "sparse_loops", ec);
    fs::remove_all(work / "sparse_refined", ec);
    fs::create_directories(work / "sparse", ec);
    // COLMAP reads every file of the folder otherwise (curate.json, the contact sheet).
    const fs::path list = work / "frames.txt";
    {
        std::ofstream f(list);
        for (const auto& n : names) f << n << "\n";
        if (!f) throw Error(list.string() + ": cannot write the frame list");
    }
    // One camera for all frames: the first frame's size decides the feature budget.
    const ImageSize size = read_image_size(frames / names.front());
    const ColmapStepOptions options = colmap_step_options(s, size.width, size.height);
    run.max_num_features = options.max_num_features;

    const std::string gpu = "0";  // Debian's COLMAP is built without CUDA
    std::vector<std::string> matching = {s.colmap, s.matcher + "_matcher", "--database_path", db.string(),
                                         "--SiftMatching.use_gpu", gpu};
    matching.insert(matching.end(), options.matching.begin(), options.matching.end());
    if (s.matcher == "sequential") {
        for (const std::string& a :
             {std::string("--SequentialMatching.overlap"), std::to_string(sequential_overlap_of(s)),
              std::string("--SequentialMatching.quadratic_overlap"),
              std::string(s.quadratic_overlap ? "1" : "0")})
            matching.push_back(a);
    }
    std::vector<std::string> extraction = {s.colmap, "feature_extractor", "--database_path", db.string(),
                                           "--image_path", frames.string(), "--image_list_path", list.string(),
                                           "--ImageReader.single_camera", "1", "--ImageReader.camera_model",
                                           s.camera_model, "--SiftExtraction.use_gpu", gpu};
    extraction.insert(extraction.end(), options.extraction.begin(), options.extraction.end());
    const auto mapping_into = [&](const fs::path& sparse) {
        std::vector<std::string> argv = {s.colmap, "mapper", "--database_path", db.string(), "--image_path",
                                         frames.string(), "--output_path", sparse.string(), "--image_list_path",
                                         list.string()};
        argv.insert(argv.end(), options.mapping.begin(), options.mapping.end());
        return argv;
    };
    const std::vector<Step> steps = {
        {"feature extraction", "feature_extractor.log", extraction},
        {"matching", "matcher.log", matching},
        {"mapping", "mapper.log", mapping_into(work / "sparse")},
    };
    for (size_t i = 0; i < steps.size(); ++i) {
        if (on_step) on_step(steps[i].name);
        run_step(int(i), steps[i], work, run);
    }
    // The mapper writes one folder per reconstruction it could not join; the largest is the scene.
    if (!read_largest_model(work / "sparse", run.model, run.model_folder))
        throw Error("COLMAP registered no frames of " + std::to_string(run.frames) + " (log " +
                    (work / "mapper.log").string() +
                    "): the frames may be too blurry, too few or too far apart; try --matcher exhaustive or "
                    "curate more frames");
    if (s.close_loops && s.matcher == "sequential" && s.quality != PosesQuality::Best) {
        std::vector<CameraPose> poses = colmap_poses(run.model);
        std::sort(poses.begin(), poses.end(),
                  [](const CameraPose& a, const CameraPose& b) { return a.name < b.name; });
        RevisitSettings rs;
        rs.overlap = sequential_overlap_of(s);
        const auto pairs = revisit_pairs(poses, rs);
        if (!pairs.empty()) {
            if (on_step) on_step("loop closure");
            const fs::path pair_list = work / "loop_pairs.txt", sparse = work / "sparse_loops";
            {
                std::ofstream f(pair_list);
                for (const auto& [a, b] : pairs) f << a << " " << b << "\n";
                if (!f) throw Error(pair_list.string() + ": cannot write the loop pairs");
            }
            fs::remove_all(sparse, ec);
            fs::create_directories(sparse, ec);
            std::vector<std::string> import = {s.colmap, "matches_importer", "--database_path", db.string(),
                                               "--match_list_path", pair_list.string(), "--match_type", "pairs",
                                               "--SiftMatching.use_gpu", gpu};
            import.insert(import.end(), options.matching.begin(), options.matching.end());
            run_step(3, {"loop matching", "loop_matcher.log", import}, work, run);
            run_step(3, {"loop mapping", "loop_mapper.log", mapping_into(sparse)}, work, run);
            run.loop_pairs = pairs.size();
            // The closed model replaces the first unless it lost frames (the new matches broke it apart).
            ColmapModel closed;
            fs::path closed_folder;
            if (read_largest_model(sparse, closed, closed_folder) &&
                closed.images.size() >= run.model.images.size()) {
                run.model = std::move(closed);
                run.model_folder = closed_folder;
            }
        }
    }
    if (s.refine_error_ratio > 0 && s.quality != PosesQuality::Best) refine_model(s, work, run, on_step);
    return run;
}

}  // namespace npt::capture
