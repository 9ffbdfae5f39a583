// Recovers camera poses for a folder of frames by running the `colmap` command-line tool (Debian's package, CPU
// only): feature extraction with one camera shared by all frames, sequential or exhaustive matching, and the
// incremental mapper, in a work folder; then picks the reconstruction that registered the most frames.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include "capture/colmap_model.h"

namespace npt::capture {

struct ColmapSettings {
    std::string matcher = "sequential";       // "sequential" (video frames in order) or "exhaustive"
    std::string camera_model = "OPENCV";      // as instant-ngp's colmap2nerf uses
    int max_image_size = 1600;                // SIFT on larger frames costs time and adds little
    std::string colmap = "colmap";            // the executable, found on PATH
    // Sequential matcher: each frame is matched with the next `sequential_overlap` ones. COLMAP's quadratic
    // overlap (also frames i + 2^k) is off: on the beer video its far pairs matched the can's and the floor's
    // look-alike sides and the mapper placed three stretches of the video on the wrong side of the object
    // (docs/benchmarks.md); neighbours alone give one continuous path.
    int sequential_overlap = 15;
    bool quadratic_overlap = false;
};

struct ColmapRun {
    ColmapModel model;
    std::filesystem::path model_folder;  // work/sparse/N that was chosen
    size_t frames = 0;                   // images in the frames folder
    double seconds[3] = {0, 0, 0};       // extraction, matching, mapping
};

// Called before each step with its name ("feature extraction", "matching", "mapping").
using ColmapStepFn = std::function<void(const std::string& step)>;

// Runs COLMAP on every .png/.jpg/.jpeg in `frames` (except curate's contact_sheet.png) with `work` as its work folder (created; an old database
// there is replaced). Throws npt::Error when colmap is missing ("install it: apt-get install colmap"), a step
// fails (naming the step and its log file in `work`, with the log's last line), or no reconstruction comes out.
ColmapRun run_colmap(const std::filesystem::path& frames, const std::filesystem::path& work,
                     const ColmapSettings& settings, const ColmapStepFn& on_step = {});

// The images of `frames` COLMAP will see, for counting.
size_t count_frames(const std::filesystem::path& frames);

}  // namespace npt::capture
