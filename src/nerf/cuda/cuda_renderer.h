// Renders what a camera sees of a NeRF model on the GPU (`nerfpt eval` and `view` with --backend cuda): the
// same image as render_view (render_view.h) up to rounding. The field is evaluated with the fused fp16
// tensor-core MLP, or with the fp32 per-point code that the CPU uses (Precision::fp32, the reference).
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "core/image.h"
#include "nerf/dataset.h"
#include "nerf/nerf_model.h"
#include "nerf/render_view.h"

namespace npt::nerf::cuda {

enum class Precision { fp16, fp32 };

class CudaViewRenderer {
  public:
    // Uploads the model's (averaged) parameters and occupancy grid. Throws npt::Error when no GPU can be used
    // or the network's shape is not supported by the fp16 kernels (fp32 takes any shape).
    explicit CudaViewRenderer(const NerfModel& model, Precision precision = Precision::fp16);
    ~CudaViewRenderer();
    CudaViewRenderer(const CudaViewRenderer&) = delete;
    CudaViewRenderer& operator=(const CudaViewRenderer&) = delete;

    // RGBA, as render_view returns it.
    Image render(const Camera& camera, const ViewOptions& options);
    // Renders into device memory only and returns the GPU time in milliseconds (CUDA events): for benchmarks.
    double render_timed(const Camera& camera, const ViewOptions& options);

    std::string device_name() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> m;
};

}  // namespace npt::nerf::cuda
