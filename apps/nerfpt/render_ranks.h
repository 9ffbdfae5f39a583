// `mpirun -np N nerfpt render ...`: the render split over MPI ranks (dist/mpi_world.h). A sequence (--frames)
// splits its frames: rank 0 finds the frames left to render (resume) and each rank renders a contiguous chunk
// of them, as a farm task would (dist/frames.h); a still splits its samples: rank r renders samples [spp r /
// N, spp (r+1) / N) of every pixel, and the ranks' sums are merged in sample order (render/sample_sums.h), so
// rank 0 writes bitwise the image of one process with the same spp. When a rank fails, every rank stops and
// rank 0 prints one line naming it.
#pragma once

#include "cmd_render.h"
#include "dist/mpi_world.h"

namespace npt::cli {

int run_render_ranks(const RenderArgs& args, const GlobalSettings& global, InterruptGuard& interrupts,
                     dist::MpiWorld& world);

}  // namespace npt::cli
