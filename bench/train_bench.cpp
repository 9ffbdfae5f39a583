// Trains lego (NeRF-synthetic) on the CPU for a fixed time and prints the test-split PSNR/SSIM at checkpoints
// (default 1, 5 and 10 minutes of training time; evaluation time is not counted), with the training rate.
// Usage: train_bench [--downscale 2] [--minutes 1,5,10] [--test-every 10] [--threads N] [--config JSON]
//                    [--data FOLDER] [--save MODEL.npt]
#include <tbb/global_control.h>

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
#include "nerf/dataset.h"
#include "nerf/matmul.h"
#include "nerf/model_file.h"
#include "nerf/render_view.h"
#include "nerf/trainer.h"

using namespace npt;

namespace {

// Ground truth on white and the render as two RGB images for the metrics.
void eval(const nerf::NerfModel& model, const nerf::Dataset& test, int every, double* psnr, double* ssim) {
    double ps = 0, ss = 0;
    int n = 0;
    for (size_t v = 0; v < test.cameras.size(); v += size_t(every), ++n) {
        const Image render = nerf::render_view(model, test.cameras[v], {});
        Image a(test.width, test.height, 3), b(test.width, test.height, 3);
        const uint8_t* gt = test.image(v);
        for (size_t p = 0; p < size_t(test.width) * test.height; ++p) {
            const float al = gt[4 * p + 3] / 255.0f;
            for (int k = 0; k < 3; ++k) {
                a.pixels[3 * p + k] = gt[4 * p + k] / 255.0f * al + (1.0f - al);
                b.pixels[3 * p + k] = render.pixels[4 * p + k];
            }
        }
        ps += npt::psnr(b, a);
        ss += npt::ssim(b, a);
    }
    *psnr = ps / n;
    *ssim = ss / n;
}

}  // namespace

int main(int argc, char** argv) {
    int downscale = 2, test_every = 10, threads = 0;
    std::vector<double> minutes = {1, 5, 10};
    std::string config_path, save_path;
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
        else if (a == "--minutes") {
            minutes.clear();
            std::stringstream ss(next());
            for (std::string t; std::getline(ss, t, ',');) minutes.push_back(std::atof(t.c_str()));
        } else {
            std::fprintf(stderr, "usage: train_bench [--downscale N] [--minutes 1,5,10] [--test-every N] "
                                 "[--threads N] [--config JSON] [--data FOLDER] [--save MODEL.npt]\n");
            return 2;
        }
    }
    std::optional<tbb::global_control> limit;
    if (threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, threads);
    try {
        nerf::Dataset train = nerf::load_dataset(data, "train");
        nerf::Dataset test = nerf::load_dataset(data, "test");
        nerf::downscale_dataset(train, downscale);
        nerf::downscale_dataset(test, downscale);
        const nerf::NerfConfig config = config_path.empty() ? nerf::NerfConfig{} : nerf::load_config(config_path);
        nerf::NerfModel model =
            nerf::create_model(config, train.aabb_scale, nerf::ngp_world_to_model(train.scale, train.offset));
        nerf::Trainer trainer(model, train);
        std::printf("lego %dx%d, %zu train views, test every %d of %zu views, matmul %s, threads %d\n",
                    train.width, train.height, train.cameras.size(), test_every, test.cameras.size(),
                    nerf::matmul_kernel_name(), threads);
        std::printf("| train time | steps | rays/s | samples/s | test PSNR dB | test SSIM | eval s |\n");
        std::printf("|---|---|---|---|---|---|---|\n");
        double rays = 0, samples = 0, train_s = 0;
        for (double m : minutes) {
            while (train_s < m * 60.0) {
                const nerf::StepStats s = trainer.step();
                rays += s.rays;
                samples += s.samples;
                train_s += s.seconds;
            }
            trainer.sync_model();
            const auto t0 = std::chrono::steady_clock::now();
            double psnr = 0, ssim = 0;
            eval(model, test, test_every, &psnr, &ssim);
            const double eval_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            std::printf("| %.1f min | %llu | %.0f | %.0f | %.2f | %.4f | %.1f |\n", train_s / 60.0,
                        (unsigned long long)trainer.steps_done(), rays / train_s, samples / train_s, psnr,
                        ssim, eval_s);
            std::fflush(stdout);
        }
        if (!save_path.empty()) nerf::save_model(save_path, model, false);
    } catch (const Error& e) {
        std::fprintf(stderr, "train_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
