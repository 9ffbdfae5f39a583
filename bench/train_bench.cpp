// Trains lego (NeRF-synthetic) for a fixed training time and prints the test-split PSNR/SSIM at checkpoints
// (evaluation time is not counted), with the training rate and, on a GPU, the device memory in use.
// Usage: train_bench [--backend cpu|cuda] [--seconds 5,15,60,300 | --minutes 1,5,10] [--downscale N]
//                    [--test-every N] [--threads N] [--config JSON] [--data FOLDER] [--save MODEL.npt]
//                    [--fp32-eval]
// Defaults: the CPU backend's old table (--downscale 2, --minutes 1,5,10, --test-every 10); with --backend cuda
// the (--downscale 1, --seconds 5,15,60,300, --test-every 4).
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/image_metrics.h"
#include "nerf/backend/nerf_backend.h"
#include "nerf/dataset.h"
#include "nerf/matmul.h"
#include "nerf/model_file.h"
#include "nerf/render_view.h"

using namespace npt;

namespace {

struct Scores {
    double psnr = 0, ssim = 0;
};

// Ground truth on white and the render as two RGB images for the metrics.
Scores eval(nerf::ViewRendererBackend& renderer, const nerf::Dataset& test, int every) {
    Scores s;
    int n = 0;
    for (size_t v = 0; v < test.cameras.size(); v += size_t(every), ++n) {
        const Image render = renderer.render(test.cameras[v], {});
        Image a(test.width, test.height, 3), b(test.width, test.height, 3);
        const uint8_t* gt = test.image(v);
        for (size_t p = 0; p < size_t(test.width) * test.height; ++p) {
            const float al = gt[4 * p + 3] / 255.0f;
            for (int k = 0; k < 3; ++k) {
                a.pixels[3 * p + k] = gt[4 * p + k] / 255.0f * al + (1.0f - al);
                b.pixels[3 * p + k] = render.pixels[4 * p + k];
            }
        }
        s.psnr += npt::psnr(b, a);
        s.ssim += npt::ssim(b, a);
    }
    s.psnr /= n;
    s.ssim /= n;
    return s;
}

std::vector<double> parse_list(const std::string& text, double scale) {
    std::vector<double> out;
    std::stringstream ss(text);
    for (std::string t; std::getline(ss, t, ',');) out.push_back(std::atof(t.c_str()) * scale);
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    int downscale = -1, test_every = -1, threads = 0;
    std::vector<double> stops;  // seconds of training
    std::string config_path, save_path, backend_name = "cpu";
    bool fp32_eval = false;
    const char* env = std::getenv("NERFPT_SHARED_DATA");
    std::filesystem::path data = std::filesystem::path(env ? env : NERFPT_SHARED_DATA) / "nerf_synthetic" / "lego";
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "train_bench: %s needs a value\n", a.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--downscale") downscale = std::atoi(next().c_str());
        else if (a == "--test-every") test_every = std::atoi(next().c_str());
        else if (a == "--threads") threads = std::atoi(next().c_str());
        else if (a == "--config") config_path = next();
        else if (a == "--data") data = next();
        else if (a == "--save") save_path = next();
        else if (a == "--backend") backend_name = next();
        else if (a == "--fp32-eval") fp32_eval = true;
        else if (a == "--minutes") stops = parse_list(next(), 60.0);
        else if (a == "--seconds") stops = parse_list(next(), 1.0);
        else {
            std::fprintf(stderr, "usage: train_bench [--backend cpu|cuda] [--seconds 5,15,60,300 | --minutes 1,5,10] "
                                 "[--downscale N] [--test-every N] [--threads N] [--config JSON] [--data FOLDER] "
                                 "[--save MODEL.npt] [--fp32-eval]\n");
            return 2;
        }
    }
    std::optional<tbb::global_control> limit;
    if (threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, threads);
    try {
        const nerf::Backend backend = nerf::choose_backend(backend_name).backend;
        const bool gpu = backend == nerf::Backend::cuda;
        if (downscale < 0) downscale = gpu ? 1 : 2;
        if (test_every < 0) test_every = gpu ? 4 : 10;
        if (stops.empty()) stops = gpu ? std::vector<double>{5, 15, 60, 300} : std::vector<double>{60, 300, 600};
        nerf::Dataset train = nerf::load_dataset(data, "train");
        nerf::Dataset test = nerf::load_dataset(data, "test");
        nerf::downscale_dataset(train, downscale);
        nerf::downscale_dataset(test, downscale);
        const nerf::NerfConfig base = gpu ? nerf::cuda_default_config() : nerf::cpu_default_config();
        const nerf::NerfConfig config = config_path.empty() ? base : nerf::load_config(config_path, base);
        nerf::NerfModel model =
            nerf::create_model(config, train.aabb_scale, nerf::ngp_world_to_model(train.scale, train.offset));
        const auto trainer = nerf::make_trainer(backend, model, train);
        std::printf("lego %dx%d, %zu train views, test every %d of %zu views, backend %s on %s%s\n", train.width,
                    train.height, train.cameras.size(), test_every, test.cameras.size(), nerf::backend_name(backend),
                    trainer->device().c_str(),
                    gpu ? "" : (std::string(", matmul ") + nerf::matmul_kernel_name()).c_str());
        if (gpu) std::printf("device memory in use after setup: %.0f MiB\n", double(trainer->device_memory_bytes()) / 1048576.0);
        std::printf("| train time | steps | steps/s | rays/s | samples/s | test PSNR dB | test SSIM | eval s |\n");
        std::printf("|---|---|---|---|---|---|---|---|\n");
        double rays = 0, samples = 0, marched = 0, train_s = 0;
        nerf::StepStats::Phases ph;
        for (double stop : stops) {
            while (train_s < stop) {
                const nerf::StepStats s = trainer->step();
                rays += s.rays;
                samples += s.samples;
                marched += s.marched;
                train_s += s.seconds;
                ph.march += s.phases.march;
                ph.forward += s.phases.forward;
                ph.loss += s.phases.loss;
                ph.backward += s.phases.backward;
                ph.grid_backward += s.phases.grid_backward;
                ph.adam += s.phases.adam;
                ph.occupancy += s.phases.occupancy;
            }
            trainer->sync_model();
            const auto t0 = std::chrono::steady_clock::now();
            const auto renderer = nerf::make_view_renderer(backend, model, nerf::ViewPrecision::fp16);
            const Scores sc = eval(*renderer, test, test_every);
            const double eval_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            std::printf("| %.0f s | %llu | %.0f | %.0f | %.0f | %.2f | %.4f | %.1f |\n", train_s,
                        (unsigned long long)trainer->steps_done(), double(trainer->steps_done()) / train_s,
                        rays / train_s, samples / train_s, sc.psnr, sc.ssim, eval_s);
            std::fflush(stdout);
        }
        const double steps = double(trainer->steps_done());
        const double phase_sum = ph.march + ph.forward + ph.loss + ph.backward + ph.grid_backward + ph.adam + ph.occupancy;
        std::printf("per step (mean of %.0f): %.3f ms wall, %.3f ms in the phases: march %.3f, field forward (all marched) "
                    "%.3f, composite+loss %.3f, MLP forward+backward (compacted) %.3f, hash-grid backward %.3f, "
                    "Adam %.3f, occupancy %.3f; %.0f marched and %.0f trained samples per step\n",
                    steps, 1e3 * train_s / steps, 1e3 * phase_sum / steps, 1e3 * ph.march / steps,
                    1e3 * ph.forward / steps, 1e3 * ph.loss / steps, 1e3 * ph.backward / steps,
                    1e3 * ph.grid_backward / steps, 1e3 * ph.adam / steps, 1e3 * ph.occupancy / steps,
                    marched / steps, samples / steps);
        if (gpu && fp32_eval) {
            const auto r16 = nerf::make_view_renderer(backend, model, nerf::ViewPrecision::fp16);
            const auto r32 = nerf::make_view_renderer(backend, model, nerf::ViewPrecision::fp32);
            const Scores a = eval(*r16, test, test_every), b = eval(*r32, test, test_every);
            std::printf("final model, test views: fp16 inference %.3f dB / %.4f, fp32 inference %.3f dB / %.4f "
                        "(difference %.3f dB)\n",
                        a.psnr, a.ssim, b.psnr, b.ssim, a.psnr - b.psnr);
        }
        if (!save_path.empty()) nerf::save_model(save_path, model, false);
    } catch (const Error& e) {
        std::fprintf(stderr, "train_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
