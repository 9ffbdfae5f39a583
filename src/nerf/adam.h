// Adam with L2 regularisation, exponential learning-rate decay and an exponential moving average of the
// parameters (tiny-cuda-nn's Ema(ExponentialDecay(Adam)) stack, as instant-ngp's NeRF config uses it).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "nerf/nerf_config.h"

namespace npt::nerf {

struct AdamState {
    std::vector<float> m;    // first moment
    std::vector<float> v;    // second moment
    std::vector<float> ema;  // moving average of the parameters, not bias-corrected
    uint64_t step = 0;       // completed steps
};

// The learning rate at a 0-based step: lr * decay_base ^ floor((step - decay_start) / decay_interval + 1)
// once step >= decay_start.
float learning_rate_at(const OptimizerConfig& cfg, uint64_t step);

// The sparse range of a SparseAdam step: parameters [begin, param_count) in entries of `entry_size`
// (a hash-grid entry's features); `reached[e]` != 0 for the entries that may have a non-zero gradient.
struct SparseEntries {
    size_t begin = 0;
    int entry_size = 1;
    uint8_t* reached = nullptr;  // one flag per entry; the step clears the flags and the entries' gradients
};

class Adam {
public:
    // l2_begin/l2_end: the parameter range that gets L2 regularisation (the MLP weights).
    Adam(const OptimizerConfig& cfg, size_t param_count, size_t l2_begin, size_t l2_end);

    // One step: g += l2 * w on the L2 range; m, v updated with bias correction; w -= lr * m_hat /
    // (sqrt(v_hat) + eps); ema = decay * ema + (1 - decay) * w. Parallel over the parameters (TBB),
    // deterministic. A non-finite gradient throws npt::Error before anything is changed.
    void step(float* params, const float* grads);

    // The same for the parameters before sparse.begin; in the sparse range only the reached entries are
    // visited, and a parameter whose gradient is exactly 0 keeps its value, m and v (tiny-cuda-nn's rule for
    // non-matrix parameters). Its moving average is brought up to date lazily, the next time its entry is
    // visited or by sync_ema: the same value as a dense EMA of an unchanged parameter, without touching the
    // whole array every step. The reached entries' gradients are reset to 0 and their flags cleared, so a
    // caller that accumulates only into reached entries never zeroes the sparse range itself.
    void step_sparse(float* params, float* grads, const SparseEntries& sparse);

    // The bias-corrected average ema / (1 - decay^step) into out (param_count floats); the parameters
    // themselves before the first step.
    void averaged_params(const float* params, float* out) const;

    // Brings every lazily kept average up to the current step (so that state().ema is the dense EMA).
    void sync_ema(const float* params);
    // m, v and the step count; ema is current only after sync_ema when step_sparse has run.
    const AdamState& state() const { return m_state; }
    uint64_t steps() const { return m_state.step; }
    // For resuming; throws npt::Error when the sizes do not match.
    void set_state(AdamState state);
    size_t param_count() const { return m_count; }

private:
    float ema_decay_pow(uint64_t k) const;  // ema_decay^k

    OptimizerConfig m_cfg;
    size_t m_count = 0, m_l2_begin = 0, m_l2_end = 0;
    AdamState m_state;
    // Lazy averages of the sparse range: per entry the step count its EMA includes (empty: all current).
    size_t m_sparse_begin = 0;
    int m_entry_size = 1;
    std::vector<uint32_t> m_ema_step;
    std::vector<float> m_decay_pow;  // ema_decay^k for small k
};

}  // namespace npt::nerf
