// Novel-view speed of a trained model: an orbit of N frames (default 120, 800x800, the `nerfpt view`
// defaults) rendered with the chosen backend, timing the render alone (GPU: CUDA events; no image download or
// file writing), after a few warm-up frames. With --data it also scores the test views at the data's size and
// at twice that, fp16 against fp32 field evaluation on the GPU, so that speed is reported at known quality.
// Usage: view_bench MODEL.npt [--backend cpu|cuda] [--frames 120] [--res 800] [--data FOLDER] [--test-every 4]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/image_metrics.h"
#include "nerf/backend/nerf_backend.h"
#include "nerf/model_file.h"
#include "nerf/orbit_camera.h"

using namespace npt;

namespace {

Image rgb_of(const Image& rgba) {
    Image out(rgba.width, rgba.height, 3);
    for (size_t p = 0; p < size_t(rgba.width) * rgba.height; ++p)
        for (int k = 0; k < 3; ++k) out.pixels[3 * p + k] = rgba.pixels[4 * p + k];
    return out;
}

Image truth_of(const nerf::Dataset& d, size_t v) {
    Image a(d.width, d.height, 3);
    const uint8_t* gt = d.image(v);
    for (size_t p = 0; p < size_t(d.width) * d.height; ++p) {
        const float al = gt[4 * p + 3] / 255.0f;
        for (int k = 0; k < 3; ++k) a.pixels[3 * p + k] = gt[4 * p + k] / 255.0f * al + (1.0f - al);
    }
    return a;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: view_bench MODEL.npt [--backend cpu|cuda] [--frames 120] [--res 800] "
                             "[--data FOLDER] [--test-every 4]\n");
        return 2;
    }
    std::string model_path = argv[1], backend_name = "cuda", data;
    int frames = 120, res = 800, test_every = 4;
    for (int i = 2; i < argc; ++i) {
        const std::string a = argv[i];
        const std::string v = i + 1 < argc ? argv[i + 1] : "";
        if (a == "--backend") backend_name = v, ++i;
        else if (a == "--frames") frames = std::atoi(v.c_str()), ++i;
        else if (a == "--res") res = std::atoi(v.c_str()), ++i;
        else if (a == "--data") data = v, ++i;
        else if (a == "--test-every") test_every = std::atoi(v.c_str()), ++i;
        else {
            std::fprintf(stderr, "view_bench: unknown option %s\n", a.c_str());
            return 2;
        }
    }
    try {
        const nerf::Backend backend = nerf::choose_backend(backend_name).backend;
        const nerf::NerfModel model = nerf::load_model(model_path);
        const auto r16 = nerf::make_view_renderer(backend, model, nerf::ViewPrecision::fp16);
        nerf::OrbitSettings orbit;
        orbit.centre = nerf::model_centre_world(model);
        orbit.distance = nerf::default_orbit_distance(model);
        orbit.width = orbit.height = res;
        std::vector<nerf::Camera> cams;
        for (int k = 0; k < frames; ++k)
            cams.push_back(nerf::orbit_camera(orbit, 2.0 * std::numbers::pi * k / frames));
        for (int k = 0; k < 3; ++k) r16->render_ms(cams[size_t(k) % cams.size()], {});
        // The GPU renderer's first-round size only moves the time: measure a few, report each.
        if (backend == nerf::Backend::cuda)
            for (int first : {4, 16, 32}) {
                nerf::ViewOptions o;
                o.gpu_first_round = first;
                std::vector<double> t;
                for (const nerf::Camera& c : cams) t.push_back(r16->render_ms(c, o));
                std::printf("  first round of %d samples per ray: median %.3f ms\n", first, median(t));
            }
        std::vector<double> ms;
        for (const nerf::Camera& c : cams) ms.push_back(r16->render_ms(c, {}));
        double sum = 0;
        for (double t : ms) sum += t;
        std::printf("%s on %s: %d frames of %dx%d, render only: median %.3f ms, mean %.3f ms (%.0f frames/s), "
                    "min %.3f, max %.3f\n",
                    nerf::backend_name(backend), r16->device().c_str(), frames, res, res, median(ms),
                    sum / double(ms.size()), 1000.0 * double(ms.size()) / sum,
                    *std::min_element(ms.begin(), ms.end()), *std::max_element(ms.begin(), ms.end()));
        if (!data.empty()) {
            const nerf::Dataset test = nerf::load_dataset(data, "test");
            const auto r32 = nerf::make_view_renderer(backend, model, nerf::ViewPrecision::fp32);
            double p16 = 0, p32 = 0, p_between_2x = 0;
            int n = 0;
            for (size_t v = 0; v < test.cameras.size(); v += size_t(test_every), ++n) {
                const Image truth = truth_of(test, v);
                p16 += psnr(rgb_of(r16->render(test.cameras[v], {})), truth);
                p32 += psnr(rgb_of(r32->render(test.cameras[v], {})), truth);
                nerf::Camera big = test.cameras[v];  // the same view at twice the size (800x800 for lego)
                big.width *= 2, big.height *= 2, big.fx *= 2, big.fy *= 2, big.cx *= 2, big.cy *= 2;
                p_between_2x += psnr(rgb_of(r16->render(big, {})), rgb_of(r32->render(big, {})));
            }
            std::printf("test views (%d): PSNR fp16 %.3f dB, fp32 %.3f dB (difference %.3f dB); at %dx%d fp16 vs "
                        "fp32 renders agree to %.1f dB PSNR\n",
                        n, p16 / n, p32 / n, p16 / n - p32 / n, test.width * 2, test.height * 2, p_between_2x / n);
        }
    } catch (const Error& e) {
        std::fprintf(stderr, "view_bench: %s\n", e.what());
        return 1;
    }
    return 0;
}
