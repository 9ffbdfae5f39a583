#include "render/renderer.h"

#include <string>

#include "core/error.h"
#include "render/cpu/cpu_renderer.h"

namespace npt::render {

RenderOptions resolve_options(const scene::Scene& scene, const RenderOptions& options) {
    RenderOptions r = options;
    if (r.width == 0 && r.height == 0) {
        r.width = scene.settings.width;
        r.height = scene.settings.height;
    }
    if (r.spp == 0) r.spp = scene.settings.spp;
    if (r.max_depth < 0) r.max_depth = scene.settings.max_depth;
    r.transparent = r.transparent || scene.settings.transparent;

    auto in_range = [](long v, long lo, long hi) { return v >= lo && v <= hi; };
    if (!in_range(r.width, 1, k_max_resolution) || !in_range(r.height, 1, k_max_resolution))
        throw Error("--res: " + std::to_string(r.width) + "x" + std::to_string(r.height) +
                    " is not a valid resolution (each side 1.." + std::to_string(k_max_resolution) + ")");
    if (static_cast<long long>(r.width) * r.height > k_max_pixels)
        throw Error("--res: " + std::to_string(r.width) + "x" + std::to_string(r.height) + " has more than " +
                    std::to_string(k_max_pixels) + " pixels");
    if (!in_range(r.spp, 1, k_max_spp))
        throw Error("--spp: " + std::to_string(r.spp) + " is out of range (1.." + std::to_string(k_max_spp) +
                    ")");
    if (!in_range(r.max_depth, 0, k_max_depth))
        throw Error("--max-depth: " + std::to_string(r.max_depth) + " is out of range (0.." +
                    std::to_string(k_max_depth) + ")");
    if (r.threads < 0 || r.threads > 4096)
        throw Error("--threads: " + std::to_string(r.threads) + " is out of range");
    if (r.aovs & ~uint32_t(k_aov_albedo | k_aov_normal | k_aov_depth))
        throw Error("--aov: unknown AOV bits " + std::to_string(r.aovs));
    if (r.backend != "cpu" && r.backend != "optix")
        throw Error("--backend: unknown backend '" + r.backend + "' (available: cpu, optix)");
    return r;
}

Image render(const scene::Scene& scene, const RenderOptions& resolved, const ProgressFn& progress,
             AovImages* aovs) {
    // The OptiX backend lives in a separate library: render/backend/render_backend.h dispatches to it.
    if (resolved.backend != "cpu")
        throw Error("render: backend '" + resolved.backend + "' is not the CPU's (use render_with_backend)");
    return cpu::render_cpu(scene, resolved, progress, aovs);
}

}  // namespace npt::render
