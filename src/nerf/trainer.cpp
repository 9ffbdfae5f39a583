#include "nerf/trainer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/error.h"
#include "core/memory.h"
#include "core/rng.h"
#include "nerf/composite.h"
#include "nerf/field_batch.h"
#include "nerf/loss.h"
#include "nerf/surface_smoothness.h"
#include "nerf/train_pixel.h"

namespace npt::nerf {

namespace {

constexpr size_t k_chunk_samples = 2048;  // field evaluation unit: fixed, so results ignore the thread count
constexpr size_t k_rays_per_task = 256;
constexpr uint32_t k_initial_rays = 1024;
constexpr int k_ngp_batch_samples = 1 << 18;

struct TrainRay {
    uint32_t first = 0, count = 0;  // samples [first, first + count) of the batch
    uint32_t image = 0;
    Rgb target, background;
};

}  // namespace

// Function-try-blocks: the optimizer state (four copies of the parameters) and a step's buffers (per sample)
// are the allocations a config decides; a bad_alloc says which setting to lower.
Trainer::Trainer(NerfModel& model, const Dataset& data) try
    : m_model(model),
      m_data(data),
      m_layout(model.layout()),
      m_march(model.march_params()),
      m_adam(model.config.optimizer, m_layout.total, m_layout.density_offset, m_layout.grid_offset) {
    if (data.cameras.empty()) throw Error("the training set has no frames");
    if (!model.training) {
        TrainingState st;
        st.params = model.params;
        model.training = std::move(st);
    }
    TrainingState& st = *model.training;
    if (st.params.size() != m_layout.total) throw Error("the model's training state does not match its layout");
    if (st.adam.step > 0 || !st.adam.m.empty()) m_adam.set_state(st.adam);
    if (st.rays_per_step == 0) st.rays_per_step = k_initial_rays;
    if (!model.config.training.exposure_per_image)
        st.exposure = {};
    else if (st.exposure.log_gain.size() != data.cameras.size())
        st.exposure = make_exposure_state(data.cameras.size());  // new, or trained on another image set
    m_grads.assign(m_layout.total, 0.0f);
    if (model.config.optimizer.sparse_grid)
        m_reached.assign((m_layout.total - m_layout.grid_offset) / size_t(m_layout.grid.features_per_level), 0);
    // The grid's schedule counts instant-ngp steps of 2^18 samples: a smaller batch stretches it, so the grid
    // costs the same share of the training work (with 2^16 samples and every-16-steps updates, the grid
    // estimate would otherwise cost as much as training itself on a CPU).
    const double stretch = double(k_ngp_batch_samples) / double(model.config.training.batch_samples);
    m_occupancy_interval =
        uint64_t(std::max(1.0, std::round(double(model.config.occupancy.update_interval) * stretch)));
} catch (const std::bad_alloc&) {
    const double total = double(model.layout().total);
    throw Error("training state (the model's " + std::to_string(size_t(total)) +
                " parameters, 5 copies) needs " + format_bytes(total * 4.0 * 5.0) +
                " of memory, more than this machine could allocate: lower encoding.log2_table_size or "
                "encoding.levels in the config");
}

void Trainer::sync_model() {
    TrainingState& st = *m_model.training;
    m_adam.sync_ema(st.params.data());
    st.adam = m_adam.state();
    m_model.params.resize(m_layout.total);
    m_adam.averaged_params(st.params.data(), m_model.params.data());
}

StepStats Trainer::step() {
    const auto t0 = std::chrono::steady_clock::now();
    StepStats stats = compute_gradient();
    TrainingState& st = *m_model.training;
    const uint64_t step = m_adam.steps();
    auto lap = [last = std::chrono::steady_clock::now()]() mutable {
        const auto now = std::chrono::steady_clock::now();
        const double s = std::chrono::duration<double>(now - last).count();
        last = now;
        return s;
    };

    // 6. Adam, then the occupancy grid with the new parameters.
    if (m_reached.empty())
        m_adam.step(st.params.data(), m_grads.data());
    else
        m_adam.step_sparse(st.params.data(), m_grads.data(),
                           SparseEntries{m_layout.grid_offset, m_layout.grid.features_per_level, m_reached.data()});
    if (!st.exposure.empty())
        exposure_step(st.exposure, m_exposure_grad, m_model.config.training.exposure_learning_rate);
    stats.phases.adam = lap();
    stats.step = m_adam.steps();
    if (step % m_occupancy_interval == 0) {
        update_occupancy(step);
        stats.occupancy_updated = true;
    }
    stats.phases.occupancy = lap();
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    st.elapsed_seconds += stats.seconds;
    return stats;
}

StepStats Trainer::gradient(std::vector<float>& grads) {
    const uint32_t rays = m_model.training->rays_per_step;
    StepStats stats = compute_gradient();
    m_model.training->rays_per_step = rays;  // nothing changes: the next step sees the same batch
    grads = m_grads;
    clear_grid_gradient();  // no Adam step follows to reset the reached entries
    return stats;
}

StepStats Trainer::compute_gradient() try {
    const auto t0 = std::chrono::steady_clock::now();
    auto lap = [last = t0]() mutable {
        const auto now = std::chrono::steady_clock::now();
        const double s = std::chrono::duration<double>(now - last).count();
        last = now;
        return s;
    };
    StepStats stats;
    TrainingState& st = *m_model.training;
    const NerfConfig& cfg = m_model.config;
    const uint64_t step = m_adam.steps();
    const uint64_t step_seed = mix64(cfg.training.seed ^ mix64(step + 1));
    // With the smoothness loss the rays come in whole groups (train_pixel.h).
    const bool grouped = cfg.loss.surface_smoothness > 0.0f;
    const float spacing = grouped ? cfg.loss.smoothness_spacing : 0.0f;
    const uint32_t n_rays = grouped ? std::max(st.rays_per_step - st.rays_per_step % k_smoothness_group,
                                               k_smoothness_group)
                                    : st.rays_per_step;
    const OccupancyGridView grid = m_model.occupancy.view();
    const Mat4& w2m = m_model.world_to_model;
    const size_t n_images = m_data.cameras.size();
    const SubjectFocus focus{m_data.subject_rects.size() == n_images ? m_data.subject_rects.data() : nullptr,
                             cfg.training.subject_rays};

    // 1. Rays and their samples, marched per task of k_rays_per_task rays.
    const size_t n_tasks = (n_rays + k_rays_per_task - 1) / k_rays_per_task;
    std::vector<std::vector<MarchSample>> task_samples(n_tasks);
    std::vector<TrainRay> rays(n_rays);
    std::vector<Vec3> ray_dirs(n_rays);
    tbb::parallel_for(size_t(0), n_tasks, [&](size_t task) {
        std::vector<MarchSample> buf(size_t(m_march.max_samples));
        auto& out = task_samples[task];
        const size_t end = std::min<size_t>(n_rays, (task + 1) * k_rays_per_task);
        for (size_t r = task * k_rays_per_task; r < end; ++r) {
            const TrainPixel draw =
                draw_train_pixel(step_seed, uint32_t(r), uint32_t(n_images), m_data.width, m_data.height,
                                 cfg.training.random_background, spacing, focus);
            const Camera& cam = m_data.cameras[draw.image];
            const int ix = std::min(int(draw.px), m_data.width - 1), iy = std::min(int(draw.py), m_data.height - 1);
            const uint8_t* pix = m_data.image(draw.image) + (size_t(iy) * m_data.width + ix) * 4;
            TrainRay& tr = rays[r];
            tr.image = draw.image;
            tr.background = draw.background;
            const float alpha = pix[3] / 255.0f;
            const Rgb rgb(pix[0] / 255.0f, pix[1] / 255.0f, pix[2] / 255.0f);
            tr.target = rgb * alpha + tr.background * (1.0f - alpha);
            const Ray world = generate_pixel_ray(cam, draw.px, draw.py);
            const Ray model{w2m.transform_point(world.o), normalize(w2m.transform_vector(world.d))};
            ray_dirs[r] = model.d;
            const int n = march_ray(m_march, grid, model, draw.jitter, buf.data());
            tr.count = uint32_t(n);
            out.insert(out.end(), buf.begin(), buf.begin() + n);
        }
    });

    // 2. Keep rays, in order, while the batch has room; drop the rest (instant-ngp does the same).
    const size_t budget = size_t(cfg.training.batch_samples);
    size_t total_marched = 0, n_kept = 0, n_samples = 0;
    for (uint32_t r = 0; r < n_rays; ++r) {
        total_marched += rays[r].count;
        if (n_kept == r && n_samples + rays[r].count <= budget) {
            rays[r].first = uint32_t(n_samples);
            n_samples += rays[r].count;
            ++n_kept;
        }
    }
    // Whole groups only: a group's smoothness term needs all three of its rays.
    for (; grouped && n_kept % k_smoothness_group != 0; --n_kept) n_samples -= rays[n_kept - 1].count;
    std::vector<Vec3> positions(n_samples), dirs(n_samples);
    std::vector<float> dts(n_samples);
    for (size_t task = 0, g = 0; task < n_tasks; ++task) {
        const auto& ts = task_samples[task];
        const size_t end = std::min<size_t>(n_kept, (task + 1) * k_rays_per_task);
        size_t k = 0;
        for (size_t r = task * k_rays_per_task; r < end; ++r)
            for (uint32_t j = 0; j < rays[r].count; ++j, ++k, ++g) {
                positions[g] = ts[k].position;
                dirs[g] = ray_dirs[r];
                dts[g] = ts[k].dt;
            }
    }

    stats.phases.march = lap();

    // 3. Field forward per chunk.
    const size_t n_chunks = (n_samples + k_chunk_samples - 1) / k_chunk_samples;
    std::vector<FieldBatch> chunks(n_chunks);
    const float* params = st.params.data();
    tbb::parallel_for(size_t(0), n_chunks, [&](size_t c) {
        const size_t b = c * k_chunk_samples, n = std::min(k_chunk_samples, n_samples - b);
        field_forward(m_layout, params, positions.data() + b, dirs.data() + b, n, true, chunks[c]);
    });
    std::vector<float> sigma(n_samples);
    std::vector<Rgb> rgb(n_samples);
    for (size_t c = 0; c < n_chunks; ++c) {
        std::copy(chunks[c].sigma.begin(), chunks[c].sigma.end(), sigma.begin() + c * k_chunk_samples);
        std::copy(chunks[c].rgb.begin(), chunks[c].rgb.end(), rgb.begin() + c * k_chunk_samples);
    }

    stats.phases.forward = lap();

    // 4. Composite, loss and its gradient per ray.
    std::vector<float> d_sigma(n_samples, 0.0f);
    std::vector<Rgb> d_rgb(n_samples);
    std::vector<double> ray_loss(n_kept), ray_se(n_kept);
    std::vector<uint32_t> ray_used(n_kept);  // samples before the ray's early stop: those with a gradient
    const bool exposure = !st.exposure.empty();
    std::vector<Rgb> ray_d_log_gain(exposure ? n_kept : 0);
    const float inv_rays = 1.0f / float(std::max<size_t>(n_kept, 1));
    const float delta = cfg.loss.huber_delta;
    auto composite_ray = [&](size_t r) {
        const TrainRay& tr = rays[r];
        const CompositeResult fwd = composite_forward(&sigma[tr.first], &rgb[tr.first], &dts[tr.first],
                                                      int(tr.count), cfg.march.min_transmittance,
                                                      tr.background);
        // The image's gain multiplies the whole composite (captures are opaque: the background is not seen).
        const Rgb gain = exposure ? exposure_gain(st.exposure, tr.image) : Rgb(1.0f);
        const Rgb pred = fwd.color * gain;
        Rgb grad;
        double loss = 0, se = 0;
        for (int k = 0; k < 3; ++k) {
            const float diff = pred[k] - tr.target[k];
            loss += huber_loss(diff, delta, &grad[k]);
            se += double(diff) * diff;
        }
        if (exposure) {
            ray_d_log_gain[r] = grad * pred * inv_rays;  // d pred / d log gain = pred
            grad = grad * gain;
        }
        ray_loss[r] = loss;
        ray_se[r] = se;
        ray_used[r] = uint32_t(fwd.used);
        if (tr.count > 0)
            composite_backward(&sigma[tr.first], &rgb[tr.first], &dts[tr.first], int(tr.count), fwd,
                               tr.background, grad * inv_rays, &d_sigma[tr.first], &d_rgb[tr.first]);
        return fwd;
    };
    std::vector<double> group_smoothness;
    if (!grouped) {
        tbb::parallel_for(size_t(0), n_kept, [&](size_t r) { composite_ray(r); });
    } else {
        // n_kept is whole groups (above).
        const size_t groups = n_kept / k_smoothness_group;
        group_smoothness.assign(groups, 0.0);
        tbb::parallel_for(size_t(0), groups, [&](size_t g) {
            const size_t r0 = g * k_smoothness_group;
            SurfacePoint points[k_smoothness_group];
            int used[k_smoothness_group] = {};
            for (uint32_t k = 0; k < k_smoothness_group; ++k) {
                const CompositeResult fwd = composite_ray(r0 + k);
                const TrainRay& tr = rays[r0 + k];
                used[k] = fwd.used;
                points[k] = surface_point(&sigma[tr.first], &positions[tr.first], &dts[tr.first], used[k]);
            }
            const SmoothnessTerm term =
                smoothness_term(points, cfg.loss.surface_smoothness, cfg.loss.smoothness_scale);
            if (!term.active) return;
            group_smoothness[g] = term.loss;
            for (uint32_t k = 0; k < k_smoothness_group; ++k) {
                const TrainRay& tr = rays[r0 + k];
                surface_point_backward_add(&sigma[tr.first], &positions[tr.first], &dts[tr.first],
                                           used[k], points[k], term.d_point[k] * inv_rays,
                                           &d_sigma[tr.first]);
            }
        });
    }

    if (exposure) {  // summed per image in ray order: reproducible whatever the thread count
        m_exposure_grad.assign(st.exposure.log_gain.size(), Rgb(0.0f));
        for (size_t r = 0; r < n_kept; ++r) m_exposure_grad[rays[r].image] += ray_d_log_gain[r];
    }
    stats.phases.loss = lap();

    // 5. Backward: MLP gradients per chunk, summed in chunk order; hash grid per level.
    const size_t mlp_params = m_layout.grid_offset;
    std::vector<float> chunk_grads(n_chunks * mlp_params, 0.0f);
    tbb::parallel_for(size_t(0), n_chunks, [&](size_t c) {
        const size_t b = c * k_chunk_samples;
        // field_backward adds into a full-layout array; only the MLP ranges [0, grid_offset) are touched.
        field_backward(m_layout, params, d_sigma.data() + b, d_rgb.data() + b, chunks[c],
                       chunk_grads.data() + c * mlp_params);
    });
    float* grads = m_grads.data();
    // Sparse: the grid range is already zero (Adam::step_sparse resets the entries it visits), and only the
    // MLPs' few parameters are cleared; dense: all of it.
    const size_t cleared = m_reached.empty() ? m_layout.total : mlp_params;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, cleared, size_t(1) << 16),
                      [&](const tbb::blocked_range<size_t>& range) {
                          std::fill(grads + range.begin(), grads + range.end(), 0.0f);
                      });
    for (size_t c = 0; c < n_chunks; ++c) {
        const float* cg = chunk_grads.data() + c * mlp_params;
        for (size_t i = 0; i < mlp_params; ++i) grads[i] += cg[i];
    }
    std::vector<const Vec3*> chunk_pos(n_chunks);
    std::vector<const FieldBatch*> chunk_ptr(n_chunks);
    for (size_t c = 0; c < n_chunks; ++c) {
        chunk_pos[c] = positions.data() + c * k_chunk_samples;
        chunk_ptr[c] = &chunks[c];
    }
    stats.phases.backward = lap();
    accumulate_grid_gradient(m_layout, chunk_pos, chunk_ptr, grads, m_reached.empty() ? nullptr : m_reached.data());
    stats.phases.grid_backward = lap();

    // The next step's ray count aims at a full batch given this step's samples per ray.
    const double per_ray = n_rays > 0 ? double(total_marched) / n_rays : 1.0;
    st.rays_per_step = uint32_t(std::clamp<double>(double(budget) / std::max(per_ray, 1.0), 64.0,
                                                   double(cfg.training.max_rays_per_batch)));

    double loss = 0, se = 0;
    size_t n_used = 0;
    for (size_t r = 0; r < n_kept; ++r) {
        loss += ray_loss[r];
        se += ray_se[r];
        n_used += ray_used[r];
    }
    stats.loss = n_kept ? loss / n_kept : 0.0;
    if (grouped) {
        double smooth = 0;
        for (double v : group_smoothness) smooth += v;
        stats.smoothness = group_smoothness.empty() ? 0.0 : smooth / double(group_smoothness.size());
    }
    stats.mse = n_kept ? se / (3.0 * n_kept) : 0.0;
    stats.rays = uint32_t(n_kept);
    stats.samples = uint32_t(n_used);
    stats.marched = uint32_t(n_samples);
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return stats;
} catch (const std::bad_alloc&) {
    throw Error(
        "a training step of " + std::to_string(m_model.config.training.batch_samples) +
        " samples needs more memory than this machine could allocate: lower training.batch_samples or "
        "training.max_rays_per_batch in the config");
}

void Trainer::clear_grid_gradient() {
    if (m_reached.empty()) return;
    const size_t nf = size_t(m_layout.grid.features_per_level);
    float* grid = m_grads.data() + m_layout.grid_offset;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, m_reached.size(), size_t(1) << 16),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t e = r.begin(); e < r.end(); ++e)
                              if (m_reached[e]) {
                                  m_reached[e] = 0;
                                  std::fill(grid + e * nf, grid + (e + 1) * nf, 0.0f);
                              }
                      });
}

void Trainer::update_occupancy(uint64_t step) {
    const OccupancyConfig& oc = m_model.config.occupancy;
    Pcg32 rng(mix64(m_model.config.training.seed ^ 0x6f63637570616e63ULL), step);
    std::vector<uint32_t> cells;
    std::vector<Vec3> positions;
    m_model.occupancy.plan_update(oc, int(step / m_occupancy_interval), rng, cells, positions);
    std::vector<float> sigma(cells.size());
    const size_t n_chunks = (cells.size() + k_chunk_samples - 1) / k_chunk_samples;
    const float* params = m_model.training->params.data();
    tbb::parallel_for(size_t(0), n_chunks, [&](size_t c) {
        const size_t b = c * k_chunk_samples, n = std::min(k_chunk_samples, cells.size() - b);
        FieldBatch batch;
        field_forward(m_layout, params, positions.data() + b, nullptr, n, false, batch);
        std::copy(batch.sigma.begin(), batch.sigma.end(), sigma.begin() + b);
    });
    m_model.occupancy.apply_update(oc, cells, sigma, m_march.min_step);
}

}  // namespace npt::nerf
