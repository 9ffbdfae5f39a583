// The NeRF field at arbitrary points on the GPU, for bakes and for tests against the CPU: sigma and colour
// from the fused fp16 tensor-core kernels, or from the fp32 per-point code the CPU uses (NerfFieldView).
#pragma once

#include <memory>
#include <vector>

#include "core/vec.h"
#include "nerf/cuda/cuda_renderer.h"
#include "nerf/nerf_model.h"

namespace npt::nerf::cuda {

// Keeps the model's parameters on the GPU between calls.
class CudaFieldEvaluator {
  public:
    CudaFieldEvaluator(const NerfModel& model, Precision precision);
    ~CudaFieldEvaluator();
    CudaFieldEvaluator(const CudaFieldEvaluator&) = delete;
    CudaFieldEvaluator& operator=(const CudaFieldEvaluator&) = delete;

    // positions in model space; dirs unit length (n of them), or null for density only (rgb then untouched).
    void evaluate(const Vec3* positions, const Vec3* dirs, size_t n, float* sigma, Rgb* rgb);

  private:
    struct Impl;
    std::unique_ptr<Impl> m;
};

// One-off: the same for a few points.
void evaluate_field(const NerfModel& model, const std::vector<Vec3>& positions, const std::vector<Vec3>& dirs,
                    Precision precision, std::vector<float>& sigma, std::vector<Rgb>& rgb);

}  // namespace npt::nerf::cuda
