// `nerfpt render --frames FIRST-LAST[:STEP]`: a shot. The scene is loaded and the renderer prepared once; each
// frame poses the scene (scene/animation.h), updates only what moved, renders with the frame's own seed and
// writes OUT with #### replaced by the frame number. Frames whose EXR reads back whole are skipped, so a killed
// or interrupted shot resumes where it stopped; a farm task renders its chunk (dist/frames.h).
#pragma once

#include "cmd_render.h"

namespace npt::cli {

int run_render_sequence(const RenderArgs& args, const GlobalSettings& global, InterruptGuard& interrupts);

}  // namespace npt::cli
