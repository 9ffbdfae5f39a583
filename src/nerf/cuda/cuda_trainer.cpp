#include "nerf/cuda/cuda_trainer.h"

#include <cuda_fp16.h>
#include <cuda_runtime.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <optional>

#include "core/cuda/device_buffer.h"
#include "core/error.h"
#include "core/rng.h"
#include "nerf/adam.h"
#include "nerf/cuda/adam_kernels.h"
#include "nerf/cuda/cuda_device.h"
#include "nerf/cuda/device_occupancy.h"
#include "nerf/cuda/fused_mlp.h"
#include "nerf/cuda/hash_grid_kernels.h"
#include "nerf/cuda/train_kernels.h"
#include "nerf/pixel_ray.h"
#include "nerf/train_pixel.h"

namespace npt::nerf::cuda {

using gpu::cuda_check;
using gpu::DeviceBuffer;

namespace {

constexpr int k_ngp_batch_samples = 1 << 18;  // the occupancy schedule counts steps of this many samples
constexpr uint32_t k_marched_per_trained = 8;  // sample buffer: this many marched samples per batch sample
constexpr uint32_t k_min_rays = 128;
constexpr float k_loss_scale = 128.0f;         // fp16 gradients are scaled by this (and unscaled in fp32)
constexpr const char* k_lower_batch = "training.cuda_batch_samples (--config)";

uint32_t round_up(uint32_t n, uint32_t m) { return (n + m - 1) / m * m; }

}  // namespace

struct CudaTrainer::Impl {
    NerfModel& model;
    const Dataset& data;
    NerfLayout layout;
    MarchParams march;
    OptimizerConfig opt;
    cudaStream_t stream = nullptr;
    uint64_t step = 0;
    uint64_t occupancy_interval = 16;
    uint32_t batch = 0, max_rays = 0, capacity = 0;
    std::string device;

    // Training images and cameras.
    DeviceBuffer<uint32_t> images;
    DeviceBuffer<RayCamera> cameras;
    DeviceBuffer<PixelRect> subject_rects;  // empty: no subject focus
    // Parameters and optimizer state.
    DeviceBuffer<float> params, grads, adam_m, adam_v, ema;
    DeviceBuffer<__half> mlp_half;
    std::optional<DeviceOccupancy> occupancy;
    // Per ray.
    DeviceBuffer<uint32_t> ray_first, ray_count;
    DeviceBuffer<Rgb> ray_target, ray_background;
    DeviceBuffer<Vec3> ray_dir;
    DeviceBuffer<float4> march_scratch;
    // Per marched sample.
    DeviceBuffer<Vec3> s_pos;
    DeviceBuffer<float> s_dt, s_sigma;
    DeviceBuffer<uint32_t> s_ray;
    DeviceBuffer<Rgb> s_rgb;
    DeviceBuffer<__half> s_enc;
    // Per compacted sample.
    DeviceBuffer<Vec3> c_pos;
    DeviceBuffer<uint32_t> c_ray;
    DeviceBuffer<float> c_d_sigma, c_d_enc;
    DeviceBuffer<Rgb> c_d_rgb;
    DeviceBuffer<__half> c_enc;
    // Counters, and their host copy in pinned memory.
    DeviceBuffer<StepCounters> counters;
    StepCounters* host_counters = nullptr;
    size_t used_bytes = 0;
    // Phase boundaries of a step (CUDA events), for StepStats::phases.
    enum Mark { m_begin, m_marched, m_evaluated, m_composited, m_backward, m_grid_backward, m_adam, m_occupancy, k_marks };
    cudaEvent_t marks[k_marks] = {};
    void mark(Mark m) { cuda_check(cudaEventRecord(marks[m], stream), "cudaEventRecord"); }

    Impl(NerfModel& m, const Dataset& d) : model(m), data(d) {}
    ~Impl() {
        for (cudaEvent_t e : marks)
            if (e) cudaEventDestroy(e);
        if (host_counters) cudaFreeHost(host_counters);
        if (stream) cudaStreamDestroy(stream);
    }

    void setup();
    void run_batch(uint32_t n_rays, uint64_t step_seed);  // up to and including the gradients
    // The step's rays: clamped, and whole groups with the smoothness loss (train_pixel.h).
    uint32_t rays_this_step(uint32_t wanted) const {
        const uint32_t n = std::clamp(wanted, k_min_rays, max_rays);
        return model.config.loss.surface_smoothness > 0.0f ? n - n % k_smoothness_group : n;
    }
    StepStats stats_after(uint32_t n_rays, double seconds);
};

void CudaTrainer::Impl::setup() {
    device = require_cuda_device();
    if (data.cameras.empty()) throw Error("the training set has no frames");
    layout = model.layout();
    std::string why;
    if (!mlp_shape_supported(layout, &why))
        throw Error("the CUDA trainer does not support this model's network (" + why +
                    "); train it with --backend cpu");
    march = model.march_params();
    opt = model.config.optimizer;
    if (!model.training) {
        TrainingState st;
        st.params = model.params;
        model.training = std::move(st);
    }
    TrainingState& st = *model.training;
    if (st.params.size() != layout.total) throw Error("the model's training state does not match its layout");
    cuda_check(cudaStreamCreate(&stream), "cudaStreamCreate");

    const TrainingConfig& tc = model.config.training;
    batch = uint32_t(tc.cuda_batch_samples);
    max_rays = batch;
    capacity = round_up(batch * k_marched_per_trained, k_mlp_rows_per_tile);
    const double stretch = double(k_ngp_batch_samples) / double(batch);
    occupancy_interval =
        uint64_t(std::max(1.0, std::round(double(model.config.occupancy.update_interval) * stretch)));

    // Images as packed RGBA words; cameras folded into model space.
    images.upload(reinterpret_cast<const uint32_t*>(data.rgba.data()), data.rgba.size() / 4,
                  "the training images", "--downscale");
    std::vector<RayCamera> rc;
    rc.reserve(data.cameras.size());
    for (const Camera& c : data.cameras) rc.push_back(make_ray_camera(c, model.world_to_model));
    cameras.upload(rc);
    if (data.subject_rects.size() == data.cameras.size()) subject_rects.upload(data.subject_rects);

    // Parameters, optimizer state (fresh or resumed).
    const size_t n = layout.total;
    params.upload(st.params, "the model parameters", "encoding.log2_table_size");
    grads.allocate(n, "the parameter gradients", "encoding.log2_table_size");
    AdamState as = st.adam;
    if (as.m.empty() && as.step == 0) {
        as.m.assign(n, 0.0f);
        as.v.assign(n, 0.0f);
        as.ema.assign(n, 0.0f);
    }
    if (as.m.size() != n || as.v.size() != n || as.ema.size() != n)
        throw Error("the model's optimizer state does not match its parameters");
    adam_m.upload(as.m, "the optimizer state", "encoding.log2_table_size");
    adam_v.upload(as.v, "the optimizer state", "encoding.log2_table_size");
    ema.upload(as.ema, "the optimizer state", "encoding.log2_table_size");
    step = as.step;
    mlp_half.allocate(k_mlp_half_weights);
    cuda_check(cudaMemset(mlp_half.data(), 0, mlp_half.bytes()), "cudaMemset");
    to_half(params.data(), uint32_t(k_mlp_param_count), mlp_half.data(), stream);
    occupancy.emplace(model.occupancy, model.config.occupancy.threshold, stream);

    ray_first.allocate(max_rays, "the ray buffers", k_lower_batch);
    ray_count.allocate(max_rays, "the ray buffers", k_lower_batch);
    ray_target.allocate(max_rays, "the ray buffers", k_lower_batch);
    ray_background.allocate(max_rays, "the ray buffers", k_lower_batch);
    ray_dir.allocate(max_rays, "the ray buffers", k_lower_batch);
    march_scratch.allocate(size_t(max_rays) * k_march_scratch, "the ray buffers", k_lower_batch);
    s_pos.allocate(capacity, "the sample buffers", k_lower_batch);
    s_dt.allocate(capacity, "the sample buffers", k_lower_batch);
    s_sigma.allocate(capacity, "the sample buffers", k_lower_batch);
    s_ray.allocate(capacity, "the sample buffers", k_lower_batch);
    s_rgb.allocate(capacity, "the sample buffers", k_lower_batch);
    s_enc.allocate(size_t(capacity) * k_mlp_inputs, "the sample buffers", k_lower_batch);
    c_pos.allocate(capacity, "the training batch", k_lower_batch);
    c_ray.allocate(capacity, "the training batch", k_lower_batch);
    c_d_sigma.allocate(capacity, "the training batch", k_lower_batch);
    c_d_rgb.allocate(capacity, "the training batch", k_lower_batch);
    c_enc.allocate(size_t(capacity) * k_mlp_inputs, "the training batch", k_lower_batch);
    c_d_enc.allocate(size_t(capacity) * k_mlp_inputs, "the training batch", k_lower_batch);
    counters.allocate(1);
    cuda_check(cudaMallocHost(&host_counters, sizeof(StepCounters)), "cudaMallocHost");
    for (cudaEvent_t& e : marks) cuda_check(cudaEventCreate(&e), "cudaEventCreate");
    if (st.rays_per_step == 0) st.rays_per_step = std::max(k_min_rays, batch / 512);
    cuda_check(cudaStreamSynchronize(stream), "uploading the model");
    size_t free_b = 0, total_b = 0;
    cudaMemGetInfo(&free_b, &total_b);
    used_bytes = total_b - free_b;
}

void CudaTrainer::Impl::run_batch(uint32_t n_rays, uint64_t step_seed) {
    mark(m_begin);
    cuda_check(cudaMemsetAsync(counters.data(), 0, sizeof(StepCounters), stream), "cudaMemsetAsync");
    StepCounters* ctr = counters.data();
    RayBuffers rays{ray_first.data(), ray_count.data(), ray_target.data(), ray_background.data(), ray_dir.data()};
    SampleBuffers samples{s_pos.data(), s_dt.data(), s_ray.data(), capacity};

    MarchRaysArgs ma;
    ma.images = {images.data(),
                 cameras.data(),
                 uint32_t(data.cameras.size()),
                 data.width,
                 data.height,
                 {subject_rects.size() ? subject_rects.data() : nullptr, model.config.training.subject_rays}};
    ma.march = march;
    ma.grid = occupancy->view();
    ma.step_seed = step_seed;
    ma.random_background = model.config.training.random_background;
    const LossConfig& lc = model.config.loss;
    ma.group_spacing = lc.surface_smoothness > 0.0f ? lc.smoothness_spacing : 0.0f;
    ma.n_rays = n_rays;
    ma.rays = rays;
    ma.samples = samples;
    ma.scratch = march_scratch.data();
    ma.occupied_box = occupancy->occupied_box();
    ma.counters = ctr;
    march_training_rays(ma, stream);
    mark(m_marched);

    // Every marched sample: encoding and the network, inference only.
    const float* grid = params.data() + layout.grid_offset;
    HashGridArgs h;
    h.layout = layout;
    h.positions = s_pos.data();
    h.count = &ctr->marched;
    h.capacity = capacity;
    hash_encode(h, grid, s_enc.data(), stream);
    MlpInferenceArgs ia;
    ia.weights = mlp_half.data();
    ia.encoded = s_enc.data();
    ia.sample_ray = s_ray.data();
    ia.ray_dir = ray_dir.data();
    ia.count = &ctr->marched;
    ia.capacity = capacity;
    ia.sigma = s_sigma.data();
    ia.rgb = s_rgb.data();
    mlp_inference(ia, false, stream);
    mark(m_evaluated);

    CompositeLossArgs ca;
    ca.n_rays = n_rays;
    ca.rays = rays;
    ca.samples = samples;
    ca.sigma = s_sigma.data();
    ca.rgb = s_rgb.data();
    ca.min_transmittance = model.config.march.min_transmittance;
    ca.huber_delta = lc.huber_delta;
    ca.smoothness_weight = lc.surface_smoothness;
    ca.smoothness_scale = lc.smoothness_scale;
    ca.compact = {c_pos.data(), c_ray.data(), c_d_sigma.data(), c_d_rgb.data(), capacity};
    ca.counters = ctr;
    composite_loss(ca, stream);
    mark(m_composited);

    // The compacted samples: forward with activations, backward, gradients.
    grads.zero_async(stream);
    HashGridArgs hc = h;
    hc.positions = c_pos.data();
    hc.count = &ctr->compacted;
    hash_encode(hc, grid, c_enc.data(), stream);
    MlpTrainArgs ta;
    ta.weights = mlp_half.data();
    ta.encoded = c_enc.data();
    ta.sample_ray = c_ray.data();
    ta.ray_dir = ray_dir.data();
    ta.count = &ctr->compacted;
    ta.capacity = capacity;
    ta.d_sigma = c_d_sigma.data();
    ta.d_rgb = c_d_rgb.data();
    ta.rays = &ctr->rays_kept;
    ta.loss_scale = k_loss_scale;
    ta.d_encoded = c_d_enc.data();
    ta.d_weights = grads.data() + layout.density_offset;
    mlp_train(ta, stream);
    mark(m_backward);
    hash_backward(hc, c_d_enc.data(), grads.data() + layout.grid_offset, stream);
    mark(m_grid_backward);
}

StepStats CudaTrainer::Impl::stats_after(uint32_t n_rays, double seconds) {
    const StepCounters& c = *host_counters;
    StepStats s;
    s.step = step;
    s.rays = c.rays_kept;
    s.samples = std::min(c.compacted, capacity);
    s.marched = std::min(c.marched, capacity);
    s.loss = c.rays_kept ? c.loss / c.rays_kept : 0.0;
    s.mse = c.rays_kept ? c.squared_error / (3.0 * c.rays_kept) : 0.0;
    if (model.config.loss.surface_smoothness > 0.0f)
        s.smoothness = c.smoothness / double((n_rays + k_smoothness_group - 1) / k_smoothness_group);
    s.seconds = seconds;
    return s;
}

CudaTrainer::CudaTrainer(NerfModel& model, const Dataset& data) : m(std::make_unique<Impl>(model, data)) {
    m->setup();
}

CudaTrainer::~CudaTrainer() = default;

uint64_t CudaTrainer::steps_done() const { return m->step; }
std::string CudaTrainer::device_name() const { return m->device; }
size_t CudaTrainer::peak_device_bytes() const { return m->used_bytes; }

StepStats CudaTrainer::step() {
    const auto t0 = std::chrono::steady_clock::now();
    Impl& I = *m;
    TrainingState& st = *I.model.training;
    const NerfConfig& cfg = I.model.config;
    const uint64_t step = I.step;
    const uint64_t step_seed = mix64(cfg.training.seed ^ mix64(step + 1));  // the CPU trainer's
    const uint32_t n_rays = I.rays_this_step(st.rays_per_step);
    I.run_batch(n_rays, step_seed);

    AdamArgs a;
    a.params = I.params.data();
    a.grads = I.grads.data();
    a.m = I.adam_m.data();
    a.v = I.adam_v.data();
    a.ema = I.ema.data();
    a.mlp_half = I.mlp_half.data();
    a.count = I.layout.total;
    a.l2_end = uint32_t(I.layout.grid_offset);
    a.half_count = uint32_t(k_mlp_param_count);
    a.lr = learning_rate_at(I.opt, step);
    a.beta1 = I.opt.beta1;
    a.beta2 = I.opt.beta2;
    a.epsilon = I.opt.epsilon;
    a.l2 = I.opt.l2_reg;
    const double t = double(step + 1);
    a.correction1 = float(1.0 / (1.0 - std::pow(double(I.opt.beta1), t)));
    a.correction2 = float(1.0 / (1.0 - std::pow(double(I.opt.beta2), t)));
    a.ema_decay = I.opt.ema_decay;
    a.nonfinite = &I.counters.data()->nonfinite;
    adam_step(a, I.stream);
    I.mark(Impl::m_adam);

    bool updated = false;
    if (step % I.occupancy_interval == 0) {
        const int64_t update_index = int64_t(step / I.occupancy_interval);
        const bool warmup = update_index * cfg.occupancy.update_interval < cfg.occupancy.warmup_steps;
        const uint64_t seed = mix64(mix64(cfg.training.seed ^ 0x6f63637570616e63ULL) ^ step);
        I.occupancy->update(cfg.occupancy, I.layout, I.params.data() + I.layout.grid_offset, I.mlp_half.data(),
                            warmup, seed, I.march.min_step, I.stream);
        updated = true;
    }
    I.mark(Impl::m_occupancy);
    cuda_check(cudaMemcpyAsync(I.host_counters, I.counters.data(), sizeof(StepCounters), cudaMemcpyDeviceToHost,
                               I.stream),
               "cudaMemcpyAsync");
    cuda_check(cudaStreamSynchronize(I.stream), "training step");
    if (I.host_counters->nonfinite)
        throw Error("a gradient is not finite (NaN or Inf) at step " + std::to_string(step) +
                    "; the training diverged (try a lower learning rate)");
    ++I.step;

    const StepCounters& c = *I.host_counters;
    // The next step's rays aim at a full batch of trained samples and at a sample buffer that holds them all.
    double next = double(n_rays) * double(I.batch) / double(std::max<uint32_t>(c.compacted, 1));
    if (c.marched > 0) next = std::min(next, double(n_rays) * double(I.capacity) / double(c.marched));
    st.rays_per_step = uint32_t(std::clamp(next, double(k_min_rays), double(I.max_rays)));

    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    st.elapsed_seconds += seconds;
    StepStats s = I.stats_after(n_rays, seconds);
    s.occupancy_updated = updated;
    auto between = [&](Impl::Mark a, Impl::Mark b) {
        float ms = 0;
        cudaEventElapsedTime(&ms, I.marks[a], I.marks[b]);
        return double(ms) * 1e-3;
    };
    s.phases.march = between(Impl::m_begin, Impl::m_marched);
    s.phases.forward = between(Impl::m_marched, Impl::m_evaluated);
    s.phases.loss = between(Impl::m_evaluated, Impl::m_composited);
    s.phases.backward = between(Impl::m_composited, Impl::m_backward);
    s.phases.grid_backward = between(Impl::m_backward, Impl::m_grid_backward);
    s.phases.adam = between(Impl::m_grid_backward, Impl::m_adam);
    s.phases.occupancy = between(Impl::m_adam, Impl::m_occupancy);
    return s;
}

StepStats CudaTrainer::gradient(std::vector<float>& grads) {
    Impl& I = *m;
    const TrainingState& st = *I.model.training;
    const uint64_t step_seed = mix64(I.model.config.training.seed ^ mix64(I.step + 1));
    const uint32_t n_rays = I.rays_this_step(st.rays_per_step);
    const auto t0 = std::chrono::steady_clock::now();
    I.run_batch(n_rays, step_seed);
    cuda_check(cudaMemcpyAsync(I.host_counters, I.counters.data(), sizeof(StepCounters), cudaMemcpyDeviceToHost,
                               I.stream),
               "cudaMemcpyAsync");
    cuda_check(cudaStreamSynchronize(I.stream), "gradient");
    grads = I.grads.download();
    return I.stats_after(n_rays, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}

void CudaTrainer::sync_model() {
    Impl& I = *m;
    cuda_check(cudaStreamSynchronize(I.stream), "training");
    TrainingState& st = *I.model.training;
    st.params = I.params.download();
    st.adam.m = I.adam_m.download();
    st.adam.v = I.adam_v.download();
    st.adam.ema = I.ema.download();
    st.adam.step = I.step;
    // The rendered parameters: the bias-corrected EMA (Adam::averaged_params), the raw ones before any step.
    I.model.params.resize(I.layout.total);
    if (I.step == 0) {
        I.model.params = st.params;
    } else {
        const float scale = float(1.0 / (1.0 - std::pow(double(I.opt.ema_decay), double(I.step))));
        for (size_t i = 0; i < I.layout.total; ++i) I.model.params[i] = st.adam.ema[i] * scale;
    }
    I.occupancy->download(I.model.occupancy, I.model.config.occupancy.threshold, I.stream);
}

}  // namespace npt::nerf::cuda
