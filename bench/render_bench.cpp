// Renders the shared reference scenes at their reference resolution and prints time, samples/s and the error
// against the Cycles reference as a table (results go to docs/benchmarks.md).
//   render_bench [--spp N] [--threads N] [--scene NAME]...   (default: cornell, 64 spp, all threads)
#include <tbb/task_arena.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/image_io.h"
#include "core/image_stats.h"
#include "render/renderer.h"
#include "scene/scene.h"

using namespace npt;

int main(int argc, char** argv) {
    int spp = 64, threads = 0, repeats = 3;
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
        else {
            std::fprintf(stderr,
                         "usage: render_bench [--spp N] [--threads N] [--repeats N] [--scene NAME]...\n");
            return 2;
        }
    }
    if (scenes.empty()) scenes = {"cornell"};
    const char* data = std::getenv("NERFPT_SHARED_DATA");
    std::filesystem::path root = data ? data : NERFPT_SHARED_DATA;

    std::printf(
        "| scene | res | spp | threads | load+build s | render s (best of %d) | Msamples/s | relMSE vs ref "
        "|\n",
        repeats);
    std::printf("|---|---|---|---|---|---|---|---|\n");
    try {
        for (const auto& name : scenes) {
            auto folder = root / "scenes" / name;
            auto t0 = std::chrono::steady_clock::now();
            scene::Scene scene = scene::load_scene(folder / "scene.gltf");
            Image ref = read_image(folder / "reference.exr");
            auto t1 = std::chrono::steady_clock::now();
            render::RenderOptions o;
            o.width = ref.width;
            o.height = ref.height;
            o.spp = spp;
            o.threads = threads;
            o = render::resolve_options(scene, o);
            double best = 1e30;
            Image img;
            for (int r = 0; r < repeats; ++r) {
                auto s = std::chrono::steady_clock::now();
                img = render::render(scene, o);
                best = std::min(best,
                                std::chrono::duration<double>(std::chrono::steady_clock::now() - s).count());
            }
            ImageComparison c = compare_images(img, ref);
            double samples = double(o.width) * o.height * o.spp;
            std::printf("| %s | %dx%d | %d | %d | %.3f | %.3f | %.3f | %.3g |\n", name.c_str(), o.width,
                        o.height, o.spp, threads > 0 ? threads : tbb::this_task_arena::max_concurrency(),
                        std::chrono::duration<double>(t1 - t0).count(), best, samples / best * 1e-6,
                        c.rel_mse);
        }
    } catch (const Error& e) {
        std::fprintf(stderr, "render_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
