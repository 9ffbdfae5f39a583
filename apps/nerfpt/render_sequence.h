// `nerfpt render --frames FIRST-LAST[:STEP]`: a shot. The scene is loaded and the renderer prepared once; each
// frame poses the scene (scene/animation.h), updates only what moved, renders with the frame's own seed and
// writes OUT with #### replaced by the frame number. Frames whose EXR reads back whole are skipped, so a killed
// or interrupted shot resumes where it stopped; a farm task renders its chunk (dist/frames.h).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "cmd_render.h"

namespace npt::cli {

// Under MPI (render_ranks.h): once the frames left to render are known, `share` turns rank 0's list into this
// rank's part of it (every rank calls it, in the same place); `rank_text` ("rank 1 of 4: ") starts this rank's
// progress lines. Empty: this process renders every frame left.
struct FrameSharing {
    std::function<std::vector<int>(const std::vector<int>& todo)> share;
    std::string rank_text;
    bool leader = true;  // the rank that says what the whole shot did ("nothing to render")
};

int run_render_sequence(const RenderArgs& args, const GlobalSettings& global, InterruptGuard& interrupts,
                        const FrameSharing& sharing = {});

}  // namespace npt::cli
