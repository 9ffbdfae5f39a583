// Adam step over the whole parameter array. Every parameter's update depends only on its own gradient and
// state, so any split into blocks gives bit-identical results; the fixed block size only keeps the TBB
// scheduling overhead small against the ~40 flops per parameter.
#include "nerf/adam.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"

namespace npt::nerf {

namespace {

constexpr size_t k_block = size_t(1) << 14;

// The first index in [0, n) whose value is not finite, or n.
size_t first_non_finite(const float* x, size_t n) {
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, n, k_block), n,
        [&](const tbb::blocked_range<size_t>& r, size_t found) {
            for (size_t i = r.begin(); i < r.end() && i < found; ++i)
                if (!std::isfinite(x[i])) return i;
            return found;
        },
        [](size_t a, size_t b) { return std::min(a, b); });
}

}  // namespace

float learning_rate_at(const OptimizerConfig& cfg, uint64_t step) {
    if (step < uint64_t(cfg.decay_start)) return cfg.learning_rate;
    const uint64_t decays = (step - uint64_t(cfg.decay_start)) / uint64_t(cfg.decay_interval) + 1;
    return float(double(cfg.learning_rate) * std::pow(double(cfg.decay_base), double(decays)));
}

Adam::Adam(const OptimizerConfig& cfg, size_t param_count, size_t l2_begin, size_t l2_end)
    : m_cfg(cfg), m_count(param_count), m_l2_begin(l2_begin), m_l2_end(l2_end) {
    if (l2_begin > l2_end || l2_end > param_count)
        throw Error("Adam: L2 range [" + std::to_string(l2_begin) + ", " + std::to_string(l2_end) +
                    ") does not lie inside the " + std::to_string(param_count) + " parameters");
    m_state.m.assign(param_count, 0.0f);
    m_state.v.assign(param_count, 0.0f);
    m_state.ema.assign(param_count, 0.0f);
}

void Adam::step(float* params, const float* grads) {
    if (const size_t bad = first_non_finite(grads, m_count); bad < m_count)
        throw Error("Adam: gradient of parameter " + std::to_string(bad) +
                    " is not finite (NaN or Inf) at step " + std::to_string(m_state.step) +
                    "; the training diverged (try a lower learning rate)");

    // Powers and corrections in double: beta2^t stays accurate over hundreds of thousands of steps.
    const double t = double(m_state.step + 1);
    const float b1 = m_cfg.beta1, b2 = m_cfg.beta2, eps = m_cfg.epsilon, l2 = m_cfg.l2_reg;
    const float correction1 = float(1.0 / (1.0 - std::pow(double(b1), t)));
    const float correction2 = float(1.0 / (1.0 - std::pow(double(b2), t)));
    const float lr = learning_rate_at(m_cfg, m_state.step);
    const float ema_decay = m_cfg.ema_decay;
    float* m = m_state.m.data();
    float* v = m_state.v.data();
    float* ema = m_state.ema.data();
    const size_t l2_begin = m_l2_begin, l2_end = m_l2_end;

    tbb::parallel_for(tbb::blocked_range<size_t>(0, m_count, k_block),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i < r.end(); ++i) {
                              float w = params[i];
                              float g = grads[i];
                              if (i >= l2_begin && i < l2_end) g += l2 * w;
                              m[i] = b1 * m[i] + (1.0f - b1) * g;
                              v[i] = b2 * v[i] + (1.0f - b2) * g * g;
                              const float m_hat = m[i] * correction1;
                              const float v_hat = v[i] * correction2;
                              w -= lr * m_hat / (std::sqrt(v_hat) + eps);
                              params[i] = w;
                              ema[i] = ema_decay * ema[i] + (1.0f - ema_decay) * w;
                          }
                      });
    ++m_state.step;
}

void Adam::averaged_params(const float* params, float* out) const {
    if (m_state.step == 0) {
        std::copy(params, params + m_count, out);
        return;
    }
    const float scale = float(1.0 / (1.0 - std::pow(double(m_cfg.ema_decay), double(m_state.step))));
    const float* ema = m_state.ema.data();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, m_count, k_block),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i < r.end(); ++i) out[i] = ema[i] * scale;
                      });
}

void Adam::set_state(AdamState state) {
    auto check = [&](const std::vector<float>& x, const char* name) {
        if (x.size() != m_count)
            throw Error(std::string("Adam: stored optimizer state '") + name + "' has " +
                        std::to_string(x.size()) + " values, but the model has " + std::to_string(m_count) +
                        " parameters");
    };
    check(state.m, "m");
    check(state.v, "v");
    check(state.ema, "ema");
    m_state = std::move(state);
}

}  // namespace npt::nerf
