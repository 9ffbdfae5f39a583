#include "nerf/backend/nerf_backend.h"

#include <tbb/info.h>

#include <chrono>

#include "core/error.h"

#if NERFPT_HAVE_CUDA
#include "nerf/cuda/cuda_device.h"
#include "nerf/cuda/cuda_field.h"
#include "nerf/cuda/cuda_renderer.h"
#include "nerf/cuda/cuda_trainer.h"
#include "nerf/cuda/cuda_wave_march.h"
#endif

namespace npt::nerf {

const char* backend_name(Backend b) { return b == Backend::cuda ? "cuda" : "cpu"; }

bool cuda_backend_built() {
#if NERFPT_HAVE_CUDA
    return true;
#else
    return false;
#endif
}

namespace {

// Empty when a GPU can be used; otherwise why not.
std::string cuda_unavailable_reason() {
#if NERFPT_HAVE_CUDA
    std::string why;
    return cuda::cuda_device_usable(&why) ? std::string() : why;
#else
    return "this nerfpt was built without CUDA";
#endif
}

std::string cpu_description() {
    return "CPU, " + std::to_string(tbb::info::default_concurrency()) + " threads";
}

class CpuTrainer final : public TrainerBackend {
  public:
    CpuTrainer(NerfModel& model, const Dataset& data) : m_trainer(model, data) {}
    StepStats step() override { return m_trainer.step(); }
    uint64_t steps_done() const override { return m_trainer.steps_done(); }
    void sync_model() override { m_trainer.sync_model(); }
    std::string device() const override { return cpu_description(); }

  private:
    Trainer m_trainer;
};

class CpuViewRenderer final : public ViewRendererBackend {
  public:
    explicit CpuViewRenderer(const NerfModel& model) : m_model(model) {}
    Image render(const Camera& camera, const ViewOptions& options,
                 const std::function<bool(size_t, size_t)>& progress) override {
        return render_view(m_model, camera, options, progress);
    }
    double render_ms(const Camera& camera, const ViewOptions& options) override {
        const auto t0 = std::chrono::steady_clock::now();
        render_view(m_model, camera, options);
        return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    }
    std::string device() const override { return cpu_description(); }

  private:
    const NerfModel& m_model;
};

#if NERFPT_HAVE_CUDA
class GpuTrainer final : public TrainerBackend {
  public:
    GpuTrainer(NerfModel& model, const Dataset& data) : m_trainer(model, data) {}
    StepStats step() override { return m_trainer.step(); }
    uint64_t steps_done() const override { return m_trainer.steps_done(); }
    void sync_model() override { m_trainer.sync_model(); }
    std::string device() const override { return m_trainer.device_name(); }
    size_t device_memory_bytes() const override { return m_trainer.peak_device_bytes(); }

  private:
    cuda::CudaTrainer m_trainer;
};

class GpuViewRenderer final : public ViewRendererBackend {
  public:
    GpuViewRenderer(const NerfModel& model, ViewPrecision p)
        : m_renderer(model, p == ViewPrecision::fp32 ? cuda::Precision::fp32 : cuda::Precision::fp16) {}
    Image render(const Camera& camera, const ViewOptions& options,
                 const std::function<bool(size_t, size_t)>& progress) override {
        Image img = m_renderer.render(camera, options);
        if (progress && !progress(size_t(camera.height), size_t(camera.height))) throw Error("interrupted");
        return img;
    }
    double render_ms(const Camera& camera, const ViewOptions& options) override {
        return m_renderer.render_timed(camera, options);
    }
    std::string device() const override { return m_renderer.device_name(); }

  private:
    cuda::CudaViewRenderer m_renderer;
};

class GpuBakeField final : public bake::BakeField {
  public:
    explicit GpuBakeField(const NerfModel& model) : m_eval(model, cuda::Precision::fp32) {}
    void density(const std::vector<Vec3>& positions, std::vector<float>& sigma) override {
        sigma.resize(positions.size());
        m_eval.evaluate(positions.data(), nullptr, positions.size(), sigma.data(), nullptr);
    }
    void colors(const std::vector<Vec3>& positions, const std::vector<Vec3>& dirs,
                std::vector<Rgb>& color) override {
        const size_t n = positions.size(), nd = dirs.size();
        std::vector<Vec3> pos(n * nd), dir(n * nd);
        for (size_t t = 0; t < n; ++t)
            for (size_t d = 0; d < nd; ++d) {
                pos[t * nd + d] = positions[t];
                dir[t * nd + d] = dirs[d];
            }
        std::vector<float> sigma(n * nd);
        color.resize(n * nd);
        m_eval.evaluate(pos.data(), dir.data(), n * nd, sigma.data(), color.data());
    }

  private:
    cuda::CudaFieldEvaluator m_eval;
};

// fp32 (the CPU's per-point code): the relight stage's samples are the CPU backend's up to rounding.
class GpuFieldQuery final : public FieldQuery {
  public:
    explicit GpuFieldQuery(const NerfModel& model) : m_model(model), m_eval(model, cuda::Precision::fp32) {}
    void evaluate(const Vec3* positions, const Vec3* dirs, size_t n, float* sigma, Rgb* rgb) override {
        m_eval.evaluate(positions, dirs, n, sigma, rgb);
    }
    bool march(std::vector<WaveRay>& rays, WaveMode mode) override {
        if (!m_marcher) m_marcher = std::make_unique<cuda::CudaWaveMarcher>(m_model);
        m_marcher->march(rays, mode);
        return true;
    }
    size_t batch_rays() const override { return size_t(1) << 20; }

  private:
    const NerfModel& m_model;
    cuda::CudaFieldEvaluator m_eval;
    std::unique_ptr<cuda::CudaWaveMarcher> m_marcher;  // made on the first march
};
#endif

}  // namespace

BackendChoice choose_backend(const std::string& requested) {
    BackendChoice c;
    if (requested == "cpu") return c;
    if (requested == "cuda") {
        const std::string why = cuda_unavailable_reason();
        if (!why.empty()) throw Error("--backend cuda: " + why + " (use --backend cpu)");
        c.backend = Backend::cuda;
        return c;
    }
    if (!requested.empty() && requested != "auto")
        throw Error("--backend: '" + requested + "' is not a backend (cpu, cuda)");
    const std::string why = cuda_unavailable_reason();
    if (why.empty()) {
        c.backend = Backend::cuda;
    } else {
        c.note = "using the CPU: " + why;
    }
    return c;
}

std::unique_ptr<TrainerBackend> make_trainer(Backend backend, NerfModel& model, const Dataset& data) {
    if (backend == Backend::cuda && model.config.training.exposure_per_image)
        throw Error("--backend cuda: training.exposure_per_image is trained by the CPU trainer only "
                    "(use --backend cpu, or set it false in the config)");
#if NERFPT_HAVE_CUDA
    if (backend == Backend::cuda) return std::make_unique<GpuTrainer>(model, data);
#endif
    if (backend == Backend::cuda) throw Error("--backend cuda: " + cuda_unavailable_reason());
    return std::make_unique<CpuTrainer>(model, data);
}

std::unique_ptr<ViewRendererBackend> make_view_renderer(Backend backend, const NerfModel& model,
                                                        ViewPrecision precision) {
#if NERFPT_HAVE_CUDA
    if (backend == Backend::cuda) return std::make_unique<GpuViewRenderer>(model, precision);
#endif
    if (backend == Backend::cuda) throw Error("--backend cuda: " + cuda_unavailable_reason());
    (void)precision;
    return std::make_unique<CpuViewRenderer>(model);
}

std::unique_ptr<FieldQuery> make_field_query(Backend backend, const NerfModel& model) {
#if NERFPT_HAVE_CUDA
    if (backend == Backend::cuda) return std::make_unique<GpuFieldQuery>(model);
#endif
    if (backend == Backend::cuda) throw Error("--backend cuda: " + cuda_unavailable_reason());
    return make_cpu_field_query(model);
}

std::unique_ptr<bake::BakeField> make_bake_field(Backend backend, const NerfModel& model) {
#if NERFPT_HAVE_CUDA
    if (backend == Backend::cuda) return std::make_unique<GpuBakeField>(model);
#endif
    if (backend == Backend::cuda) throw Error("--backend cuda: " + cuda_unavailable_reason());
    (void)model;
    return nullptr;
}

}  // namespace npt::nerf
