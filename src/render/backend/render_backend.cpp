#include "render/backend/render_backend.h"

#include "core/error.h"
#include "render/cpu/cpu_renderer.h"

#if NERFPT_HAVE_OPTIX
#include "nerf/cuda/cuda_device.h"
#include "render/gpu/optix_renderer.h"
#endif

namespace npt::render {

bool optix_backend_built() {
#if NERFPT_HAVE_OPTIX
    return true;
#else
    return false;
#endif
}

namespace {

std::string optix_unavailable_reason() {
#if NERFPT_HAVE_OPTIX
    std::string why;
    return nerf::cuda::cuda_device_usable(&why) ? std::string() : why;
#else
    return "this nerfpt was built without the OptiX backend (no OptiX SDK headers at build time)";
#endif
}
}  // namespace

std::string choose_render_backend(const std::string& requested, std::string* note) {
    if (note) note->clear();
    if (requested == "cpu") return "cpu";
    if (requested == "optix") {
        const std::string why = optix_unavailable_reason();
        if (!why.empty()) throw Error("--backend optix: " + why + " (use --backend cpu)");
        return "optix";
    }
    if (!requested.empty() && requested != "auto")
        throw Error("--backend: '" + requested + "' is not a renderer (cpu, optix)");
    const std::string why = optix_unavailable_reason();
    if (why.empty()) return "optix";
    // Only worth a note where the GPU renderer exists and could have been used.
    if (note && optix_backend_built()) *note = "rendering on the CPU: " + why;
    return "cpu";
}

PartialFilm SceneRenderer::render_partial(const RenderOptions& resolved, uint32_t, uint32_t, const ProgressFn&) {
    throw Error("--backend " + resolved.backend +
                ": a still's samples split over MPI ranks are rendered on the CPU backend only so far (--backend "
                "cpu; sequences, --frames, split their frames over ranks on any backend)");
}

namespace {

class CpuSceneRenderer final : public SceneRenderer {
  public:
    CpuSceneRenderer(const scene::Scene& scene, const RenderOptions& resolved)
        : m_renderer(scene, resolved.width, resolved.height) {}
    void update(const scene::PoseChanges& changes) override { m_renderer.update(changes); }
    Image render(const RenderOptions& resolved, const ProgressFn& progress, Image* denoised,
                 AovImages* aovs) override {
        if (denoised) throw Error("--denoise: the denoiser is OptiX's and needs --backend optix");
        return m_renderer.render(resolved, progress, aovs);
    }
    PartialFilm render_partial(const RenderOptions& resolved, uint32_t begin, uint32_t end,
                               const ProgressFn& progress) override {
        return m_renderer.render_partial(resolved, begin, end, progress);
    }

  private:
    cpu::CpuFrameRenderer m_renderer;
};

#if NERFPT_HAVE_OPTIX
class OptixSceneRenderer final : public SceneRenderer {
  public:
    OptixSceneRenderer(const scene::Scene& scene, const RenderOptions& resolved)
        : m_renderer(scene, resolved.width, resolved.height) {}
    void update(const scene::PoseChanges& changes) override { m_renderer.update(changes); }
    Image render(const RenderOptions& resolved, const ProgressFn& progress, Image* denoised,
                 AovImages* aovs) override {
        return m_renderer.render(resolved, progress, denoised, aovs);
    }
    const Image& render_frame(const RenderOptions& resolved) override { return m_renderer.render_frame(resolved); }
    void render_into(const RenderOptions& resolved, Image& out, const ProgressFn& progress,
                     AovImages* aovs) override {
        m_renderer.render_into(resolved, out, progress, aovs);
    }
    std::shared_ptr<void> pin(Image& image) override { return gpu::OptixRenderer::pin(image); }

  private:
    gpu::OptixRenderer m_renderer;
};
#endif

}  // namespace

std::unique_ptr<SceneRenderer> prepare_renderer(const scene::Scene& scene, const RenderOptions& resolved) {
#if NERFPT_HAVE_OPTIX
    if (resolved.backend == "optix") return std::make_unique<OptixSceneRenderer>(scene, resolved);
#endif
    if (resolved.backend == "optix") throw Error("--backend optix: " + optix_unavailable_reason());
    return std::make_unique<CpuSceneRenderer>(scene, resolved);
}

Image render_with_backend(const scene::Scene& scene, const RenderOptions& resolved, const ProgressFn& progress,
                          Image* denoised, AovImages* aovs) {
    return prepare_renderer(scene, resolved)->render(resolved, progress, denoised, aovs);
}

}  // namespace npt::render
