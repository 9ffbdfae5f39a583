// Adam steps, dense over the whole parameter array or sparse over a hash grid's reached entries. Every
// parameter's update depends only on its own gradient and state, so any split into blocks gives bit-identical
// results; the fixed block size only keeps the TBB scheduling overhead small against the ~40 flops per
// parameter.
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
    // ema_decay^k for the gaps lazy averages see most (0.95^256 ~ 2e-6: longer gaps are rare and exact anyway).
    m_decay_pow.resize(256);
    for (size_t k = 0; k < m_decay_pow.size(); ++k)
        m_decay_pow[k] = float(std::pow(double(cfg.ema_decay), double(k)));
}

namespace {

// What one step applies to every parameter it updates.
struct StepConstants {
    float b1, b2, eps, l2, correction1, correction2, lr, ema_decay;
};

// The constants of the step after `step` completed ones. Powers and corrections in double: beta2^t stays
// accurate over hundreds of thousands of steps.
StepConstants step_constants(const OptimizerConfig& cfg, uint64_t step) {
    const double t = double(step + 1);
    return {cfg.beta1,
            cfg.beta2,
            cfg.epsilon,
            cfg.l2_reg,
            float(1.0 / (1.0 - std::pow(double(cfg.beta1), t))),
            float(1.0 / (1.0 - std::pow(double(cfg.beta2), t))),
            learning_rate_at(cfg, step),
            cfg.ema_decay};
}

// m, v and w of one parameter for gradient g (L2 already added); returns the new w.
inline float adam_update(const StepConstants& k, float w, float g, float& m, float& v) {
    m = k.b1 * m + (1.0f - k.b1) * g;
    v = k.b2 * v + (1.0f - k.b2) * g * g;
    const float m_hat = m * k.correction1;
    const float v_hat = v * k.correction2;
    return w - k.lr * m_hat / (std::sqrt(v_hat) + k.eps);
}

// Every parameter of [begin, end) updated, with L2 on [l2_begin, l2_end), and its average with it.
void dense_update(const StepConstants& k, size_t begin, size_t end, size_t l2_begin, size_t l2_end, float* params,
                  const float* grads, AdamState& st) {
    float* m = st.m.data();
    float* v = st.v.data();
    float* ema = st.ema.data();
    tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, k_block), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            float g = grads[i];
            if (i >= l2_begin && i < l2_end) g += k.l2 * params[i];
            const float w = adam_update(k, params[i], g, m[i], v[i]);
            params[i] = w;
            ema[i] = k.ema_decay * ema[i] + (1.0f - k.ema_decay) * w;
        }
    });
}

// An average kept lazily, brought over k steps in which its parameter stayed at w (dk = ema_decay^k): what k
// dense updates give.
inline float caught_up(float ema, float w, float dk) { return dk * ema + (1.0f - dk) * w; }

[[noreturn]] void throw_non_finite(size_t parameter, uint64_t step) {
    throw Error("Adam: gradient of parameter " + std::to_string(parameter) + " is not finite (NaN or Inf) at step " +
                std::to_string(step) + "; the training diverged (try a lower learning rate)");
}

}  // namespace

float Adam::ema_decay_pow(uint64_t k) const {
    return k < m_decay_pow.size() ? m_decay_pow[k]
                                  : float(std::pow(double(m_cfg.ema_decay), double(k)));
}

void Adam::step(float* params, const float* grads) {
    if (const size_t bad = first_non_finite(grads, m_count); bad < m_count) throw_non_finite(bad, m_state.step);
    sync_ema(params);  // lazily kept averages (step_sparse) first: this step updates every average
    m_ema_step.clear();
    dense_update(step_constants(m_cfg, m_state.step), 0, m_count, m_l2_begin, m_l2_end, params, grads, m_state);
    ++m_state.step;
}

void Adam::step_sparse(float* params, float* grads, const SparseEntries& sparse) {
    const size_t es = size_t(std::max(sparse.entry_size, 1));
    if (sparse.entry_size < 1 || sparse.begin < m_l2_end || sparse.begin > m_count ||
        (m_count - sparse.begin) % es != 0 || (sparse.begin < m_count && !sparse.reached))
        throw Error("Adam: the sparse range from parameter " + std::to_string(sparse.begin) + " in entries of " +
                    std::to_string(sparse.entry_size) + " does not divide the " + std::to_string(m_count) +
                    " parameters after the L2 range");
    const size_t entries = (m_count - sparse.begin) / es;
    if (!m_ema_step.empty() && (m_sparse_begin != sparse.begin || m_entry_size != int(es))) {
        sync_ema(params);  // another split of the parameters: every average current, then tracked anew
        m_ema_step.clear();
    }
    if (m_ema_step.empty()) {
        m_sparse_begin = sparse.begin;
        m_entry_size = int(es);
        m_ema_step.assign(entries, uint32_t(m_state.step));
    }
    const uint8_t* reached = sparse.reached;

    // Every gradient this step reads is finite, or nothing changes.
    size_t bad = first_non_finite(grads, sparse.begin);
    if (bad == sparse.begin) {
        bad = tbb::parallel_reduce(
            tbb::blocked_range<size_t>(0, entries, k_block), m_count,
            [&](const tbb::blocked_range<size_t>& r, size_t found) {
                for (size_t e = r.begin(); e < r.end() && found == m_count; ++e)
                    if (reached[e])
                        for (size_t f = 0; f < es; ++f)
                            if (!std::isfinite(grads[sparse.begin + e * es + f])) return sparse.begin + e * es + f;
                return found;
            },
            [](size_t a, size_t b) { return std::min(a, b); });
    }
    if (bad < m_count) throw_non_finite(bad, m_state.step);

    const StepConstants k = step_constants(m_cfg, m_state.step);
    // The dense part (the MLPs): every parameter, as step() does.
    dense_update(k, 0, sparse.begin, m_l2_begin, m_l2_end, params, grads, m_state);
    float* m = m_state.m.data();
    float* v = m_state.v.data();
    float* ema = m_state.ema.data();
    // The reached entries, in entry order (each entry's update is independent: any split is bit-identical).
    const uint32_t now = uint32_t(m_state.step);  // steps done before this one
    uint8_t* flags = sparse.reached;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, entries, k_block), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t e = r.begin(); e < r.end(); ++e) {
            if (!flags[e]) continue;
            flags[e] = 0;
            // The average over the steps that did not visit this entry (its parameters did not change).
            const float dk = ema_decay_pow(uint32_t(now - m_ema_step[e]));
            m_ema_step[e] = now + 1;
            for (size_t i = sparse.begin + e * es, end = i + es; i < end; ++i) {
                float w = params[i];
                const float g = grads[i];
                const float average = caught_up(ema[i], w, dk);
                if (g != 0.0f) {
                    w = adam_update(k, w, g, m[i], v[i]);
                    params[i] = w;
                    grads[i] = 0.0f;
                }
                ema[i] = k.ema_decay * average + (1.0f - k.ema_decay) * w;
            }
        }
    });
    ++m_state.step;
}

void Adam::sync_ema(const float* params) {
    if (m_ema_step.empty()) return;
    const uint32_t now = uint32_t(m_state.step);
    const size_t es = size_t(m_entry_size), begin = m_sparse_begin;
    float* ema = m_state.ema.data();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, m_ema_step.size(), k_block),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t e = r.begin(); e < r.end(); ++e) {
                              if (m_ema_step[e] == now) continue;
                              const float dk = ema_decay_pow(uint32_t(now - m_ema_step[e]));
                              m_ema_step[e] = now;
                              for (size_t i = begin + e * es, end = i + es; i < end; ++i)
                                  ema[i] = caught_up(ema[i], params[i], dk);
                          }
                      });
}

void Adam::averaged_params(const float* params, float* out) const {
    if (m_state.step == 0) {
        std::copy(params, params + m_count, out);
        return;
    }
    const float scale = float(1.0 / (1.0 - std::pow(double(m_cfg.ema_decay), double(m_state.step))));
    const float* ema = m_state.ema.data();
    const size_t dense_end = m_ema_step.empty() ? m_count : m_sparse_begin;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, dense_end, k_block),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i < r.end(); ++i) out[i] = ema[i] * scale;
                      });
    if (m_ema_step.empty()) return;
    const uint32_t now = uint32_t(m_state.step);
    const size_t es = size_t(m_entry_size);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, m_ema_step.size(), k_block),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t e = r.begin(); e < r.end(); ++e) {
                              const float dk = ema_decay_pow(uint32_t(now - m_ema_step[e]));
                              for (size_t i = m_sparse_begin + e * es, end = i + es; i < end; ++i)
                                  out[i] = caught_up(ema[i], params[i], dk) * scale;
                          }
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
    m_ema_step.clear();  // a stored state's averages are current
}

}  // namespace npt::nerf
