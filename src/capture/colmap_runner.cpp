#include "capture/colmap_runner.h"


#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <vector>

#include "core/error.h"
#include "core/executable.h"

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

}  // namespace

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
    run.frames = count_frames(frames);
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
    fs::create_directories(work / "sparse", ec);
    // COLMAP reads every file of the folder otherwise (curate.json, the contact sheet).
    const fs::path list = work / "frames.txt";
    {
        std::ofstream f(list);
        for (const auto& n : list_frames(frames)) f << n << "\n";
        if (!f) throw Error(list.string() + ": cannot write the frame list");
    }

    const std::string gpu = "0";  // Debian's COLMAP is built without CUDA
    struct Step {
        const char* name;
        const char* log;
        std::vector<std::string> argv;
    };
    std::vector<std::string> matching = {s.colmap, s.matcher + "_matcher", "--database_path", db.string(),
                                         "--SiftMatching.use_gpu", gpu};
    if (s.matcher == "sequential") {
        for (const std::string& a : {std::string("--SequentialMatching.overlap"), std::to_string(s.sequential_overlap),
                                     std::string("--SequentialMatching.quadratic_overlap"),
                                     std::string(s.quadratic_overlap ? "1" : "0")})
            matching.push_back(a);
    }
    const std::vector<Step> steps = {
        {"feature extraction", "feature_extractor.log",
         {s.colmap, "feature_extractor", "--database_path", db.string(), "--image_path", frames.string(),
          "--image_list_path", list.string(),
          "--ImageReader.single_camera", "1", "--ImageReader.camera_model", s.camera_model,
          "--SiftExtraction.use_gpu", gpu, "--SiftExtraction.max_image_size", std::to_string(s.max_image_size)}},
        {"matching", "matcher.log", matching},
        {"mapping", "mapper.log",
         {s.colmap, "mapper", "--database_path", db.string(), "--image_path", frames.string(), "--output_path",
          (work / "sparse").string(), "--image_list_path", list.string()}},
    };
    for (size_t i = 0; i < steps.size(); ++i) {
        if (on_step) on_step(steps[i].name);
        const auto t0 = std::chrono::steady_clock::now();
        const fs::path log = work / steps[i].log;
        const int status = run_logged(steps[i].argv, log);
        run.seconds[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (status != 0)
            throw Error("COLMAP " + std::string(steps[i].name) + " failed (exit " + std::to_string(status) +
                        "; log " + log.string() + "): " + last_line_of(log));
    }
    // The mapper writes one folder per reconstruction it could not join; the largest is the scene.
    size_t best = 0;
    for (const auto& e : fs::directory_iterator(work / "sparse", ec)) {
        if (!e.is_directory() || !fs::exists(e.path() / "images.bin")) continue;
        ColmapModel m = read_colmap_model(e.path());
        if (m.images.size() > best) {
            best = m.images.size();
            run.model = std::move(m);
            run.model_folder = e.path();
        }
    }
    if (best == 0)
        throw Error("COLMAP registered no frames of " + std::to_string(run.frames) + " (log " +
                    (work / "mapper.log").string() +
                    "): the frames may be too blurry, too few or too far apart; try --matcher exhaustive or "
                    "curate more frames");
    return run;
}

}  // namespace npt::capture
