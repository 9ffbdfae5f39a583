// Renders the shared reference scenes at their reference resolution and prints time, samples/s and the error
// against the Cycles reference as a table (results go to docs/benchmarks.md).
//   render_bench [--backend cpu|optix] [--spp N] [--res WxH] [--threads N] [--scene NAME]...
//   (default: the CPU, cornell at its reference resolution, 64 spp, all threads). The OptiX time includes its
//   setup (acceleration structures, pipeline) once per render, as a user's `nerfpt render` pays it.
#include <tbb/task_arena.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/image_io.h"
#include "core/image_stats.h"
#include "render/backend/render_backend.h"
#include "render/renderer.h"
#include "scene/scene.h"

using namespace npt;

int main(int argc, char** argv) {
    int spp = 64, threads = 0, repeats = 3, width = 0, height = 0;
    std::string backend = "cpu";
    std::vector<std::string> scenes;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "render_bench: %s needs a value\n", a.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--spp")
            spp = std::atoi(next().c_str());
        else if (a == "--threads")
            threads = std::atoi(next().c_str());
        else if (a == "--repeats")
            repeats = std::atoi(next().c_str());
        else if (a == "--scene")
            scenes.push_back(next());
        else if (a == "--backend")
            backend = next();
        else if (a == "--res") {
            const std::string r = next();
            if (std::sscanf(r.c_str(), "%dx%d", &width, &height) != 2) {
                std::fprintf(stderr, "render_bench: --res WxH\n");
                return 2;
            }
        }
        else {
            std::fprintf(stderr,
                         "usage: render_bench [--backend cpu|optix] [--spp N] [--res WxH] [--threads N] [--repeats N] "
                         "[--scene NAME]...\n");
            return 2;
        }
    }
    if (scenes.empty()) scenes = {"cornell"};
    const char* data = std::getenv("NERFPT_SHARED_DATA");
    std::filesystem::path root = data ? data : NERFPT_SHARED_DATA;

    std::printf(
        "| scene | backend | res | spp | threads | load s | render s (best of %d) | Msamples/s | relMSE vs ref "
        "|\n",
        repeats);
    std::printf("|---|---|---|---|---|---|---|---|---|\n");
    try {
        for (const auto& name : scenes) {
            auto folder = root / "scenes" / name;
            auto t0 = std::chrono::steady_clock::now();
            scene::Scene scene = scene::load_scene(folder / "scene.gltf");
            Image ref = read_image(folder / "reference.exr");
            auto t1 = std::chrono::steady_clock::now();
            render::RenderOptions o;
            o.width = width > 0 ? width : ref.width;
            o.height = height > 0 ? height : ref.height;
            o.spp = spp;
            o.threads = threads;
            o.backend = render::choose_render_backend(backend, nullptr);
            o = render::resolve_options(scene, o);
            double best = 1e30;
            Image img;
            for (int r = 0; r < repeats; ++r) {
                auto s = std::chrono::steady_clock::now();
                img = render::render_with_backend(scene, o);
                best = std::min(best,
                                std::chrono::duration<double>(std::chrono::steady_clock::now() - s).count());
            }
            // The error against the reference only at its own resolution.
            const double rel_mse =
                img.width == ref.width && img.height == ref.height ? compare_images(img, ref).rel_mse : -1.0;
            double samples = double(o.width) * o.height * o.spp;
            std::printf("| %s | %s | %dx%d | %d | %d | %.3f | %.3f | %.3f | %.3g |\n", name.c_str(),
                        o.backend.c_str(), o.width, o.height, o.spp,
                        threads > 0 ? threads : tbb::this_task_arena::max_concurrency(),
                        std::chrono::duration<double>(t1 - t0).count(), best, samples / best * 1e-6, rel_mse);
        }
    } catch (const Error& e) {
        std::fprintf(stderr, "render_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
