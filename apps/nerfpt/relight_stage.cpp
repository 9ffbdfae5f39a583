#include "relight_stage.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>

#include "core/progress.h"
#include "interrupt.h"
#include "nerf/backend/nerf_backend.h"
#include "nerf/relight/relight_samples.h"
#include "nerf/relight/relight_trainer.h"
#include "nerf/trainer.h"
#include "status_line.h"

namespace npt::cli {

bool run_relight_stage(nerf::NerfModel& model, const nerf::Dataset& data, const RelightStageOptions& options,
                       InterruptGuard& interrupts) {
    const auto t0 = std::chrono::steady_clock::now();
    const bool gpu = options.backend != nerf::Backend::cpu;
    nerf::RelightSampleSettings ss;
    ss.points = options.points ? options.points : (gpu ? k_relight_points_gpu : k_relight_points_cpu);
    ss.directions =
        options.directions ? options.directions : (gpu ? k_relight_directions_gpu : k_relight_directions_cpu);
    ss.event_draws = options.event_draws;
    ss.normals = options.normals;
    ss.normal_smoothing = options.normal_smoothing;
    ss.borrowing_pixels = options.borrowing_pixels >= 0 ? options.borrowing_pixels
                                                        : (gpu ? k_relight_pixels_gpu : k_relight_pixels_cpu);
    ss.pooled_neighbours = options.pooled_neighbours;
    const uint64_t seed = options.seed_given ? options.seed : model.config.training.seed;
    ss.seed = seed;
    StatusLine line(stream_is_tty(stderr), options.quiet);
    std::unique_ptr<nerf::FieldQuery> query = nerf::make_field_query(options.backend, model);
    const nerf::RelightSamples samples =
        nerf::gather_relight_samples(model, data, *query, ss, [&](size_t done, size_t total) {
            line.show(fmt::format("relight: surface points {} {:3.0f}% {}/{}",
                                  format_bar(double(done) / total, 20), 100.0 * done / total, done, total),
                      done == total);
        });
    line.finish();
    const double gather_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (samples.lit < samples.size())
        spdlog::info(
            "relight: {} surface points x {} directions and {} pixels borrowing their light in {:.1f} s",
            samples.lit, samples.directions, samples.size() - samples.lit, gather_s);
    else
        spdlog::info("relight: {} surface points x {} directions in {:.1f} s", samples.size(),
                     samples.directions, gather_s);
    if (interrupts.stop_requested()) return false;

    nerf::RelightTrainSettings ts;
    ts.seed = seed;
    ts.average_decay = options.average_decay;
    ts.intrinsic.grid.log2_table_size = options.table_log2;
    ts.intrinsic.finest_resolution = options.finest_resolution;
    ts.intrinsic.diffuse = options.diffuse_lobe;
    ts.batch = options.batch ? options.batch : (gpu ? k_relight_batch_gpu : k_relight_batch_cpu);
    ts.specular = options.specular;
    ts.diffuse = options.diffuse;
    ts.roughness_prior = options.roughness_prior;
    ts.huber_delta = options.huber_delta;
    ts.ground_share = options.ground_share;
    ts.footprint_queries = options.footprint_queries;
    nerf::RelightTrainer trainer(model, data.cameras.size(), samples, ts);
    nerf::RelightStepStats st;
    while (trainer.steps_done() < options.steps) {
        st = trainer.step();
        const double frac = double(trainer.steps_done()) / double(options.steps);
        line.show(
            fmt::format("relight: fit {} {:3.0f}% step {} psnr {:.2f} dB normal {:.4f}", format_bar(frac, 20),
                        100.0 * frac, st.step, nerf::psnr_from_mse(st.mse), st.normal_loss),
            trainer.steps_done() == options.steps);
        if (interrupts.stop_requested()) {
            line.finish();
            return false;
        }
    }
    line.finish();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    model.relight = trainer.fields(seconds);
    spdlog::info("relight: {} steps, last batch psnr {:.2f} dB (sRGB, the capture light), {:.1f} s in all",
                 trainer.steps_done(), nerf::psnr_from_mse(st.mse), seconds);
    return true;
}

}  // namespace npt::cli
