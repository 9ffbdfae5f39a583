#include "render/backend/render_backend.h"

#include "core/error.h"

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

// OptiX becomes the default renderer once its parity tests (tests/gpu/optix_render_test.cpp) have passed on a
// GPU; until then it is used only when asked for with --backend optix.
constexpr bool k_optix_is_default = false;

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
    if (!k_optix_is_default) return "cpu";
    const std::string why = optix_unavailable_reason();
    if (why.empty()) return "optix";
    // Only worth a note where the GPU renderer exists and could have been used.
    if (note && optix_backend_built()) *note = "rendering on the CPU: " + why;
    return "cpu";
}

Image render_with_backend(const scene::Scene& scene, const RenderOptions& resolved, const ProgressFn& progress,
                          Image* denoised) {
#if NERFPT_HAVE_OPTIX
    if (resolved.backend == "optix") return gpu::render_optix(scene, resolved, progress, denoised);
#endif
    if (resolved.backend == "optix") throw Error("--backend optix: " + optix_unavailable_reason());
    if (denoised) throw Error("--denoise: the denoiser is OptiX's and needs --backend optix");
    return render(scene, resolved, progress);
}

}  // namespace npt::render
