// Renders scenes and prints time, samples/s and the error against a reference as a table (results go to
// docs/benchmarks.md).
//   render_bench [--backend cpu|optix] [--spp N] [--res WxH] [--threads N] [--repeats N] [--frames N]
//                [--scene NAME]... [--scene-file PATH]...
//   --scene NAME: a shared reference scene (../shared/data/scenes/NAME, compared with its reference.exr);
//   --scene-file PATH: any scene (no reference). Default: the CPU, cornell at its reference resolution, 64 spp.
// Columns: setup (scene on the device, acceleration structure, pipeline; per render on the CPU backend) is
// timed apart from the render; with --frames N, N more renders of the prepared scene (seeds 1..N) into the
// renderer's own frame (render_frame: on OptiX page-locked and reused) give the frame rate an interactive viewer
// would see, each frame downloaded to the host.
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

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Job {
    std::string name;
    std::filesystem::path scene, reference;  // reference: empty when there is none
};

}  // namespace

int main(int argc, char** argv) {
    int spp = 64, threads = 0, repeats = 3, frames = 0, width = 0, height = 0;
    std::string backend = "cpu";
    std::vector<Job> jobs;
    const char* data = std::getenv("NERFPT_SHARED_DATA");
    const std::filesystem::path root = data ? data : NERFPT_SHARED_DATA;
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
        else if (a == "--frames")
            frames = std::atoi(next().c_str());
        else if (a == "--scene") {
            const std::string name = next();
            jobs.push_back({name, root / "scenes" / name / "scene.gltf", root / "scenes" / name / "reference.exr"});
        } else if (a == "--scene-file") {
            const std::filesystem::path p = next();
            jobs.push_back({p.filename().string(), p, {}});
        } else if (a == "--backend")
            backend = next();
        else if (a == "--res") {
            const std::string r = next();
            if (std::sscanf(r.c_str(), "%dx%d", &width, &height) != 2) {
                std::fprintf(stderr, "render_bench: --res WxH\n");
                return 2;
            }
        } else {
            std::fprintf(stderr,
                         "usage: render_bench [--backend cpu|optix] [--spp N] [--res WxH] [--threads N] [--repeats N] "
                         "[--frames N] [--scene NAME]... [--scene-file PATH]...\n");
            return 2;
        }
    }
    if (spp < 1 || repeats < 1 || frames < 0) {
        std::fprintf(stderr, "render_bench: --spp and --repeats must be >= 1, --frames >= 0\n");
        return 2;
    }
    if (jobs.empty()) jobs.push_back({"cornell", root / "scenes/cornell/scene.gltf", root / "scenes/cornell/reference.exr"});

    std::printf("| scene | backend | res | spp | threads | load s | setup s | render s (best of %d) | Msamples/s | "
                "relMSE vs ref | frames/s (%d frames) |\n",
                repeats, frames);
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
    try {
        for (const Job& job : jobs) {
            auto t0 = std::chrono::steady_clock::now();
            scene::Scene scene = scene::load_scene(job.scene);
            Image ref;
            if (!job.reference.empty()) ref = read_image(job.reference);
            const double load = seconds_since(t0);
            render::RenderOptions o;
            o.width = width;
            o.height = height;
            if (width <= 0 && ref.width > 0) o.width = ref.width, o.height = ref.height;
            o.spp = spp;
            o.threads = threads;
            o.backend = render::choose_render_backend(backend, nullptr);
            o = render::resolve_options(scene, o);
            t0 = std::chrono::steady_clock::now();
            const auto renderer = render::prepare_renderer(scene, o);
            const double setup = seconds_since(t0);
            double best = 1e30;
            Image img;
            for (int r = 0; r < repeats; ++r) {
                t0 = std::chrono::steady_clock::now();
                img = renderer->render(o);
                best = std::min(best, seconds_since(t0));
            }
            double fps = 0.0;
            if (frames > 0) {
                t0 = std::chrono::steady_clock::now();
                for (int f = 1; f <= frames; ++f) {
                    o.seed = uint64_t(f);
                    renderer->render_frame(o);
                }
                fps = frames / seconds_since(t0);
            }
            // The error against the reference only at its own resolution.
            const double rel_mse =
                img.width == ref.width && img.height == ref.height ? compare_images(img, ref).rel_mse : -1.0;
            const double samples = double(o.width) * o.height * o.spp;
            std::printf("| %s | %s | %dx%d | %d | %d | %.3f | %.3f | %.4f | %.3f | %.3g | %.1f |\n", job.name.c_str(),
                        o.backend.c_str(), o.width, o.height, o.spp,
                        threads > 0 ? threads : tbb::this_task_arena::max_concurrency(), load, setup, best,
                        samples / best * 1e-6, rel_mse, fps);
            std::fflush(stdout);
        }
    } catch (const Error& e) {
        std::fprintf(stderr, "render_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
