// The intrinsic fields of a relightable model seen from a data set's cameras: per pixel, the albedo and the
// normal (training world, the data set's axes) of camera-ray scattering events drawn from the volume weights,
// averaged over the events `spp` draws find (what a relit render's first-event AOVs converge to), as
// `albedo_N.exr` / `normal_N.exr` (and `roughness_N.exr`, grey) for
// ../shared/data/relight/score.py (run it with --normals-zup). Prints a table of time and coverage.
//   relight_fields MODEL.npt DATA/transforms_test.json OUT_DIR [--spp 8] [--backend cpu|cuda]
//                  [--normals predicted|density|depth] [--normal-step 0.004] [--normal-pixels 2]
//                  [--at events|mean]
// Also prints the events' spread in depth: per pixel with events on every draw, the standard deviation of
// their distance along the camera ray, in units of the pixel's footprint at that distance (median and 90th
// percentile over the views' pixels). Draws of one pixel pass through different places in it, so a slanted
// surface adds its slope to the spread; on surfaces facing the camera it is the density shell's thickness,
// which blurs the fields where the events fall off the surface (docs/benchmarks.md, issue 24).
// --at mean queries the albedo and roughness once per pixel, at the mean of its rays' event positions (about
// the expected termination point), instead of averaging them over the events: how much the events' spread in
// depth about the surface blurs the albedo (docs/benchmarks.md, issue 24).
// --normals measures an estimator of surface_normals.h instead of the fitted normal field (the model then
// need not be relightable; the albedo is written only for relightable models): what the relight stage's
// targets are worth against the ground truth.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>

#include "core/error.h"
#include "core/image_io.h"
#include "core/progress.h"
#include "core/rng.h"
#include "nerf/backend/nerf_backend.h"
#include "nerf/dataset.h"
#include "nerf/model_file.h"
#include "nerf/relight/surface_normals.h"
#include "nerf/relight/wavefront_march.h"

using namespace npt;
using namespace npt::nerf;

int main(int argc, char** argv) try {
    if (argc < 4) {
        fmt::print(stderr, "usage: relight_fields MODEL.npt TRANSFORMS.json OUT_DIR [--spp N] [--backend cpu|cuda] "
                           "[--normals predicted|density|depth] [--normal-step S] [--normal-pixels P] "
                           "[--at events|mean]\n");
        return 2;
    }
    int spp = 8;
    std::string backend_name, normals_mode = "predicted", at_mode = "events";
    float normal_step = 0.004f, normal_pixels = 2.0f;
    for (int i = 4; i + 1 < argc; i += 2) {
        if (std::strcmp(argv[i], "--spp") == 0) spp = std::max(1, std::atoi(argv[i + 1]));
        if (std::strcmp(argv[i], "--backend") == 0) backend_name = argv[i + 1];
        if (std::strcmp(argv[i], "--normals") == 0) normals_mode = argv[i + 1];
        if (std::strcmp(argv[i], "--normal-step") == 0) normal_step = float(std::atof(argv[i + 1]));
        if (std::strcmp(argv[i], "--normal-pixels") == 0) normal_pixels = float(std::atof(argv[i + 1]));
        if (std::strcmp(argv[i], "--at") == 0) at_mode = argv[i + 1];
    }
    if (at_mode != "events" && at_mode != "mean") throw Error("--at: '" + at_mode + "' is not events or mean");
    if (normals_mode != "predicted" && normals_mode != "density" && normals_mode != "depth")
        throw Error("--normals: '" + normals_mode + "' is not predicted, density or depth");
    const NerfModel model = load_model(argv[1]);
    const bool fitted = model.relightable();
    if (!fitted && normals_mode == "predicted")
        throw Error(std::string(argv[1]) + ": the model is not relightable (measure --normals density or depth)");
    const Dataset data = load_dataset(argv[2], "");
    const std::filesystem::path out = argv[3];
    std::filesystem::create_directories(out);
    const Backend backend = choose_backend(backend_name).backend;
    auto query = make_field_query(backend, model);
    const IntrinsicFieldView intrinsic = fitted ? model.intrinsic() : IntrinsicFieldView{};
    const Mat4 m2w = model.world_to_model.inverse();
    const double t0 = Progress::steady_seconds();
    double coverage = 0;
    std::vector<float> spreads;  // the events' depth spread per pixel, in pixel footprints
    for (size_t v = 0; v < data.cameras.size(); ++v) {
        const Camera& cam = data.cameras[v];
        const int W = data.width, H = data.height;
        std::vector<WaveRay> rays(size_t(W) * H * spp);
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x)
                for (int s = 0; s < spp; ++s) {
                    Pcg32 rng = Pcg32::for_pixel(v, uint32_t(x), uint32_t(y), uint32_t(s));
                    const Ray world = generate_pixel_ray(cam, x + rng.next_float(), y + rng.next_float());
                    WaveRay& r = rays[(size_t(y) * W + x) * spp + s];
                    r.ray = Ray{model.world_to_model.transform_point(world.o),
                                normalize(model.world_to_model.transform_vector(world.d))};
                    r.jitter = rng.next_float();
                    r.tau_target = -std::log1p(-std::min(rng.next_float(), 0.999999f));
                }
        march_wavefront(model, *query, rays, WaveMode::event);
        // The estimator's normal per ray (model space), when not the fitted field's.
        std::vector<Vec3> estimate;
        if (normals_mode == "density") {
            std::vector<Vec3> at(rays.size()), toward(rays.size());
            for (size_t i = 0; i < rays.size(); ++i) {
                at[i] = rays[i].event_position;
                toward[i] = -rays[i].ray.d;
            }
            estimate = density_normals(*query, at, toward, normal_step);
        } else if (normals_mode == "depth") {
            std::vector<PixelRef> pixels(rays.size());
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x)
                    for (int s = 0; s < spp; ++s) {
                        Pcg32 rng = Pcg32::for_pixel(v, uint32_t(x), uint32_t(y), uint32_t(s));
                        const float fx = rng.next_float(), fy = rng.next_float();
                        pixels[(size_t(y) * W + x) * spp + s] = PixelRef{uint32_t(v), x + fx, y + fy, rng.next_float()};
                    }
            estimate = depth_stencil_normals(model, *query, data.cameras, pixels, normal_pixels);
        }
        Image albedo(W, H, 3), normal(W, H, 3), roughness(W, H, 3);  // roughness in R, G and B: EXR wants 3 or 4
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                Rgb a(0.0f);
                Vec3 n(0.0f);
                float rough = 0.0f;
                int hits = 0;
                double t_sum = 0, t_sq = 0;
                Vec3 mean_position(0.0f);
                int events = 0;
                for (int s = 0; at_mode == "mean" && s < spp; ++s) {
                    const WaveRay& r = rays[(size_t(y) * W + x) * spp + s];
                    if (r.has_event) {
                        mean_position += r.event_position;
                        ++events;
                    }
                }
                if (events) mean_position = mean_position * (1.0f / float(events));
                const IntrinsicSample at_mean =
                    fitted && events && at_mode == "mean" ? intrinsic.query(mean_position) : IntrinsicSample{};
                for (int s = 0; s < spp; ++s) {
                    const size_t i = (size_t(y) * W + x) * spp + s;
                    const WaveRay& r = rays[i];
                    if (!r.has_event) continue;
                    const double t = length(r.event_position - r.ray.o);
                    t_sum += t;
                    t_sq += t * t;
                    Vec3 nm;
                    if (fitted) {
                        const IntrinsicSample is = at_mode == "mean" ? at_mean : intrinsic.query(r.event_position);
                        a += is.albedo;
                        rough += is.roughness;
                        nm = is.normal;
                    }
                    if (!estimate.empty()) {
                        nm = estimate[i];
                        if (!(dot(nm, nm) > 0.0f)) continue;  // the estimator has none here
                    }
                    Vec3 nw = normalize(m2w.transform_vector(nm));
                    if (dot(nw, m2w.transform_vector(r.ray.d)) > 0.0f) nw = -nw;  // toward the camera
                    n += nw;
                    ++hits;
                }
                coverage += double(hits) / spp;
                if (hits == spp && spp > 1) {
                    const double mean_t = t_sum / hits, var = std::max(0.0, t_sq / hits - mean_t * mean_t);
                    // Model units per pixel at that distance.
                    const double footprint = mean_t / double(cam.fx);
                    if (footprint > 0) spreads.push_back(float(std::sqrt(var) / footprint));
                }
                // Averaged over the draws that found an event, as the renderer's first-hit AOVs are (not
                // darkened where some rays miss: the ground truth is compared unpremultiplied).
                const float inv = hits ? 1.0f / float(hits) : 0.0f;
                a = a * inv;
                n = n * inv;
                rough *= inv;
                std::memcpy(albedo.at(x, y), &a, 12);
                std::memcpy(normal.at(x, y), &n, 12);
                for (int c = 0; c < 3; ++c) roughness.at(x, y)[c] = rough;
            }
        write_exr(out / fmt::format("albedo_{}.exr", v), albedo);  // zero when not fitted (score.py wants one)
        write_exr(out / fmt::format("normal_{}.exr", v), normal);
        if (fitted) write_exr(out / fmt::format("roughness_{}.exr", v), roughness);
    }
    const double secs = Progress::steady_seconds() - t0;
    fmt::print("| views | size | spp | normals | backend | seconds | mean coverage |\n|---|---|---|---|---|---|---|\n");
    fmt::print("| {} | {}x{} | {} | {} | {} | {:.1f} | {:.3f} |\n", data.cameras.size(), data.width, data.height, spp,
               normals_mode == "density" ? fmt::format("density, step {}", normal_step)
               : normals_mode == "depth" ? fmt::format("depth, {} px", normal_pixels) : normals_mode,
               backend_name.empty() ? "auto" : backend_name, secs,
               coverage / (double(data.cameras.size()) * data.width * data.height));
    if (!spreads.empty()) {
        std::sort(spreads.begin(), spreads.end());
        fmt::print(
            "events' depth spread (std, pixel footprints) over {} fully covered pixels: median {:.2f}, "
            "90th percentile {:.2f}\n",
            spreads.size(), spreads[spreads.size() / 2], spreads[spreads.size() * 9 / 10]);
    }
    return 0;
} catch (const std::exception& e) {
    fmt::print(stderr, "relight_fields: error: {}\n", e.what());
    return 1;
}
