// Recovers camera poses for a folder of frames by running the `colmap` command-line tool (Debian's package,
// CPU only): feature extraction with one camera shared by all frames, sequential or exhaustive matching, and
// the incremental mapper, in a work folder; then picks the reconstruction that registered the most frames.
// The faster qualities then close the loops of a video (capture/revisit_pairs.h): frames that revisit an
// earlier view are matched with it and the mapper runs again with those matches. Last, they refine the model:
// the observations far above its mean reprojection error are dropped and a global bundle adjustment runs
// again.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "capture/colmap_model.h"

namespace npt::capture {

// How much work COLMAP spends on the poses (`--poses-quality`). Measured in docs/benchmarks.md ("How fast
// COLMAP can be"): `best` is COLMAP's own extraction, matching and mapper settings (what nerfpt ran before
// the option existed); `balanced` and `fast` cap the SIFT features with a budget that follows the image size
// and run fewer, shorter bundle adjustments; `fast` extracts at the frame's own size, not doubled, keeps
// every scale there with one orientation per keypoint, and matches each frame with its next 5 instead of 15.
enum class PosesQuality { Fast, Balanced, Best };
PosesQuality parse_poses_quality(const std::string& name);  // "fast", "balanced", "best"; throws npt::Error
const char* poses_quality_name(PosesQuality quality);

struct ColmapSettings {
    std::string matcher = "sequential";       // "sequential" (video frames in order) or "exhaustive"
    std::string camera_model = "OPENCV";      // as instant-ngp's colmap2nerf uses
    int max_image_size = 1600;                // SIFT on larger frames costs time and adds little
    std::string colmap = "colmap";            // the executable, found on PATH
    // Sequential matcher: each frame is matched with the next `sequential_overlap` ones (0: the quality's,
    // sequential_overlap_of). COLMAP's quadratic overlap (also frames i + 2^k) is off: on the beer video its
    // far pairs matched the can's and the floor's look-alike sides and the mapper placed three stretches of
    // the video on the wrong side of the object (docs/benchmarks.md); neighbours alone give one continuous
    // path.
    int sequential_overlap = 0;
    bool quadratic_overlap = false;
    // After a sequential matcher's first model: match the frames whose cameras revisit an earlier view and map
    // again (fast and balanced; best is COLMAP's own pipeline). On the handheld capture the rotation error fell
    // from 0.89° to 0.28° (docs/benchmarks.md, "Poses as accurate as before the speed-up").
    bool close_loops = true;
    // After the last model (fast and balanced): drop the observations that reproject more than this many
    // times the model's mean reprojection error (`colmap point_filtering`) and adjust the whole model again
    // (`colmap bundle_adjuster`); 0: off. The mapper keeps observations up to 2 px (COLMAP's default: 4), about
    // 4x the mean of a 540x960 capture's model, and enough of them are wrong to bend the path: on four handheld
    // captures the rotation error's median fell by 21-27% (docs/benchmarks.md, "Refining the model:
    // observations over twice the mean error dropped").
    double refine_error_ratio = 2.0;
    PosesQuality quality = PosesQuality::Fast;
    int threads = 0;  // every step's num_threads; 0: all hardware threads (passed explicitly all the same)
};

// The options of each COLMAP step that the quality and the frame size decide (after the database, image and
// camera arguments every run passes), for run_colmap and for tests.
struct ColmapStepOptions {
    std::vector<std::string> extraction, matching, mapping;
    int max_num_features = 0;  // the SIFT budget per frame that was chosen
};
ColmapStepOptions colmap_step_options(const ColmapSettings& settings, int frame_width, int frame_height);
// The sequential matcher's overlap the settings ask for: theirs, else the quality's.
int sequential_overlap_of(const ColmapSettings& settings);

// Extraction, matching, mapping, loop closure (matching the revisiting pairs and mapping again), refinement
// (filtering the observations and adjusting again).
constexpr int k_colmap_steps = 5;

struct ColmapRun {
    ColmapModel model;
    std::filesystem::path model_folder;  // work/sparse/N or work/sparse_loops/N that was chosen
    size_t frames = 0;                   // images in the frames folder
    double seconds[k_colmap_steps] = {};  // wall time of each step (0: not run)
    // The same steps' CPU time (user + system of COLMAP's threads), and the machine's 1-minute load average
    // when each started: wall time means something only on a quiet machine, CPU time everywhere.
    double cpu_seconds[k_colmap_steps] = {};
    double load_at_start[k_colmap_steps] = {};
    int max_num_features = 0;  // SIFT budget per frame (ColmapStepOptions)
    size_t loop_pairs = 0;     // revisiting pairs matched by the loop closure (0: none found or not run)
    // Refinement: the threshold used (0: not run), and the mean reprojection error before and after (px).
    double refine_threshold_px = 0, refine_error_before_px = 0, refine_error_after_px = 0;
    std::string refine_skipped;  // why the refinement's model was not used (a step failed, ...); empty: used
};

// Called before each step with its name ("feature extraction", "matching", "mapping", "loop closure",
// "refinement").
using ColmapStepFn = std::function<void(const std::string& step)>;

// Runs COLMAP on every .png/.jpg/.jpeg in `frames` (except curate's contact_sheet.png) with `work` as its work folder (created; an old database
// there is replaced). Throws npt::Error when colmap is missing ("install it: apt-get install colmap"), a step
// fails (naming the step and its log file in `work`, with the log's last line), or no reconstruction comes out.
ColmapRun run_colmap(const std::filesystem::path& frames, const std::filesystem::path& work,
                     const ColmapSettings& settings, const ColmapStepFn& on_step = {});

// The images of `frames` COLMAP will see, for counting.
size_t count_frames(const std::filesystem::path& frames);

}  // namespace npt::capture
