// The relight stage's wavefront march (nerf/relight/wavefront_march.h) done wholly on the GPU: the rays'
// state stays on the device, each round marches every live ray a few samples (the view renderer's
// march_into_slots), evaluates them in one launch and composites them by march_wavefront's arithmetic, so
// that the host's CPU cores (which limited the stage on some machines) do nothing but wait. The results equal
// the CPU's march up to float rounding.
#pragma once

#include <memory>
#include <vector>

#include "nerf/nerf_model.h"
#include "nerf/relight/wave_ray.h"

namespace npt::nerf::cuda {

class CudaWaveMarcher {
  public:
    // Uploads the model's parameters and occupancy grid. Throws npt::Error when no GPU can be used. The field
    // is evaluated in fp32 by the CPU's per-point code (NerfFieldView), so that the relight stage's samples
    // are the CPU backend's up to rounding.
    explicit CudaWaveMarcher(const NerfModel& model);
    ~CudaWaveMarcher();
    CudaWaveMarcher(const CudaWaveMarcher&) = delete;
    CudaWaveMarcher& operator=(const CudaWaveMarcher&) = delete;

    // Marches the rays (their results overwritten) as march_wavefront does.
    void march(std::vector<WaveRay>& rays, WaveMode mode);

  private:
    struct Impl;
    std::unique_ptr<Impl> m;
};

}  // namespace npt::nerf::cuda
