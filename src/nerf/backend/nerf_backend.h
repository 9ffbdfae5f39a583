// Where NeRF work runs: the CPU (TBB) or a CUDA GPU. The front ends (CLI, benchmarks, tests) choose a backend
// here and get a trainer or a view renderer behind one small interface, so that none of them needs CUDA
// headers or #ifdefs. Built with CUDA, `cuda` is the default where a GPU is present; otherwise `cpu`, with
// one line saying why.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "bake/bake_grid.h"
#include "core/image.h"
#include "nerf/dataset.h"
#include "nerf/nerf_model.h"
#include "nerf/relight/field_query.h"
#include "nerf/render_view.h"
#include "nerf/trainer.h"

namespace npt::nerf {

enum class Backend { cpu, cuda };

const char* backend_name(Backend b);

struct BackendChoice {
    Backend backend = Backend::cpu;
    std::string note;  // why the default fell back to the CPU ("" when nothing to say)
};

// requested: "" or "auto" (cuda when this binary has CUDA and a GPU is usable, else cpu with a note), "cpu",
// or "cuda" (npt::Error naming the reason when no GPU can be used: no silent fallback). Anything else is an
// npt::Error.
BackendChoice choose_backend(const std::string& requested);

// True when this binary was built with the CUDA backend.
bool cuda_backend_built();

class TrainerBackend {
  public:
    virtual ~TrainerBackend() = default;
    virtual StepStats step() = 0;
    virtual uint64_t steps_done() const = 0;
    // Parameters, optimizer state and occupancy grid into the model (before saving or evaluating it).
    virtual void sync_model() = 0;
    virtual std::string device() const = 0;  // "CPU, 2 threads" or the GPU's name
    virtual size_t device_memory_bytes() const { return 0; }  // GPU memory in use after setup (0 on the CPU)
};

std::unique_ptr<TrainerBackend> make_trainer(Backend backend, NerfModel& model, const Dataset& data);

enum class ViewPrecision { fp16, fp32 };  // the CUDA renderer's field evaluation; the CPU is always fp32

class ViewRendererBackend {
  public:
    virtual ~ViewRendererBackend() = default;
    // RGBA as render_view returns it; progress as render_view's (the GPU calls it once at the end).
    virtual Image render(const Camera& camera, const ViewOptions& options,
                         const std::function<bool(size_t, size_t)>& progress = {}) = 0;
    // The render alone (no image download), in milliseconds: GPU time from CUDA events, wall time on the CPU.
    virtual double render_ms(const Camera& camera, const ViewOptions& options) = 0;
    virtual std::string device() const = 0;
};

// The field evaluator a bake uses on this backend: nullptr for the CPU (bake_model's own parallel path); on the
// GPU the fp32 per-point code, so that a GPU bake is the CPU's up to rounding. The model must outlive it.
std::unique_ptr<bake::BakeField> make_bake_field(Backend backend, const NerfModel& model);

// Batched NeRF evaluation for the relight stage's wavefront marcher: parallel CPU chunks, or the GPU's fp32
// per-point code (the CPU's maths up to rounding). The model must outlive it.
std::unique_ptr<FieldQuery> make_field_query(Backend backend, const NerfModel& model);

// The model must outlive the renderer.
std::unique_ptr<ViewRendererBackend> make_view_renderer(Backend backend, const NerfModel& model,
                                                        ViewPrecision precision = ViewPrecision::fp16);

}  // namespace npt::nerf
