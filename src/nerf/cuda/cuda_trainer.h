// Trains a NerfModel on the GPU: the CPU trainer's step (trainer.h) as CUDA kernels, with instant-ngp's
// sample compaction. One step: march random pixels' rays through the occupancy grid; evaluate the field on
// every marched sample (inference only); composite each ray against its random background, take the Huber
// loss and its gradient; keep the samples in front of each ray's early stop and run the fused forward +
// backward MLP kernel and the hash-grid backward on those alone; Adam with the EMA; every few steps the
// occupancy grid. The model file is the CPU's: sync_model() puts parameters, optimizer state and occupancy
// back into the NerfModel, so a GPU-trained model resumes, evaluates and renders anywhere.
// Sums of gradients use atomics, so unlike the CPU trainer a run is not bit-for-bit reproducible.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "nerf/dataset.h"
#include "nerf/nerf_model.h"
#include "nerf/trainer.h"

namespace npt::nerf::cuda {

class CudaTrainer {
  public:
    // Uploads the data set and the model (with its training state, if any, to resume). Throws npt::Error when
    // no GPU can be used, the model's network has a shape the kernels do not support, or memory runs out.
    CudaTrainer(NerfModel& model, const Dataset& data);
    ~CudaTrainer();
    CudaTrainer(const CudaTrainer&) = delete;
    CudaTrainer& operator=(const CudaTrainer&) = delete;

    StepStats step();
    uint64_t steps_done() const;
    // Parameters (raw and averaged), Adam's state, the occupancy grid, step and ray count into the model.
    void sync_model();

    // The gradient step() would apply next (mean loss over the kept rays, before L2), into grads (the
    // model's layout); nothing changes. For tests against the CPU trainer.
    StepStats gradient(std::vector<float>& grads);

    std::string device_name() const;
    size_t peak_device_bytes() const;  // device memory in use after setup, from cudaMemGetInfo

  private:
    struct Impl;
    std::unique_ptr<Impl> m;
};

}  // namespace npt::nerf::cuda
