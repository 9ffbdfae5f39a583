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

class Adam {
public:
    // l2_begin/l2_end: the parameter range that gets L2 regularisation (the MLP weights).
    Adam(const OptimizerConfig& cfg, size_t param_count, size_t l2_begin, size_t l2_end);

    // One step: g += l2 * w on the L2 range; m, v updated with bias correction; w -= lr * m_hat /
    // (sqrt(v_hat) + eps); ema = decay * ema + (1 - decay) * w. Parallel over the parameters (TBB),
    // deterministic. A non-finite gradient throws npt::Error before anything is changed.
    void step(float* params, const float* grads);

    // The bias-corrected average ema / (1 - decay^step) into out (param_count floats); the parameters
    // themselves before the first step.
    void averaged_params(const float* params, float* out) const;

    const AdamState& state() const { return m_state; }
    // For resuming; throws npt::Error when the sizes do not match.
    void set_state(AdamState state);
    size_t param_count() const { return m_count; }

private:
    OptimizerConfig m_cfg;
    size_t m_count = 0, m_l2_begin = 0, m_l2_end = 0;
    AdamState m_state;
};

}  // namespace npt::nerf
