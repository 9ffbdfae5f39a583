// Adam: one and three steps against values worked out from the formulas in double (L2 on a sub-range, a
// learning-rate decay inside the three steps), the decay schedule, the EMA's bias correction, and the errors;
// the sparse step against a dense reference of tiny-cuda-nn's rule (a zero gradient in the sparse range leaves
// the parameter and its moments alone; the average still moves every step).
#include "nerf/adam.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "test_support.h"

namespace npt::nerf {
namespace {

OptimizerConfig test_config() {
    OptimizerConfig c;
    c.learning_rate = 0.1f;
    c.beta1 = 0.9f;
    c.beta2 = 0.99f;
    c.epsilon = 1e-8f;
    c.l2_reg = 0.5f;
    c.decay_start = 2;  // steps 0 and 1 at 0.1, step 2 at 0.05
    c.decay_interval = 1;
    c.decay_base = 0.5f;
    c.ema_decay = 0.95f;
    return c;
}

// Parameters 1 and 2 get L2; parameter 3 has a zero first gradient (m = v = 0: it must not move).
const std::vector<float> k_start = {1.0f, -2.0f, 0.25f, 3.0f};
const float k_grads[3][4] = {
    {0.5f, -1.0f, 0.2f, 0.0f}, {-0.25f, 0.5f, 0.4f, 1.0f}, {0.125f, 0.75f, -0.3f, -2.0f}};

// Float arithmetic against double references of order 1: a few float ulps.
constexpr double k_tol = 1e-6;

TEST(Adam, OneStepMovesByTheLearningRateTowardsMinusTheGradient) {
    Adam adam(test_config(), 4, 1, 3);
    std::vector<float> w = k_start;
    adam.step(w.data(), k_grads[0]);
    // t = 1: m_hat = g and v_hat = g^2, so w -= lr * g / (|g| + eps) = lr * sign(g) (up to eps/|g|), where
    // g includes L2 on [1, 3): g1 = -1 + 0.5 * -2 = -2, g2 = 0.2 + 0.5 * 0.25 = 0.325.
    EXPECT_NEAR(w[0], 1.0 - 0.1 * 0.5 / (0.5 + 1e-8), k_tol);
    EXPECT_NEAR(w[1], -2.0 + 0.1 * 2.0 / (2.0 + 1e-8), k_tol);
    EXPECT_NEAR(w[2], 0.25 - 0.1 * 0.325 / (0.325 + 1e-8), k_tol);
    EXPECT_EQ(w[3], 3.0f);
    EXPECT_EQ(adam.state().step, 1u);
    EXPECT_NEAR(adam.state().m[1], 0.1 * -2.0, k_tol);
    EXPECT_NEAR(adam.state().v[1], 0.01 * 4.0, k_tol);
}

TEST(Adam, ThreeStepsMatchTheFormulas) {
    Adam adam(test_config(), 4, 1, 3);
    std::vector<float> w = k_start;
    for (const auto& g : k_grads) adam.step(w.data(), g);
    // Worked out in double from m = b1 m + (1-b1) g, v = b2 v + (1-b2) g^2, m_hat = m / (1-b1^t),
    // v_hat = v / (1-b2^t), w -= lr_t m_hat / (sqrt(v_hat) + eps) with lr = 0.1, 0.1, 0.05 and
    // g += 0.5 w on parameters 1 and 2.
    const double expected[4] = {0.8562533426762062, -1.784014205892268, 0.029969677330911472,
                                2.9414117471046284};
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(w[i], expected[i], k_tol) << i;

    // ema = 0.95 ema + 0.05 w after each step, divided by 1 - 0.95^3.
    const double expected_avg[4] = {0.8757815604770353, -1.8320694542095746, 0.0748943367835855,
                                    2.954733766240596};
    std::vector<float> avg(4);
    adam.averaged_params(w.data(), avg.data());
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(avg[i], expected_avg[i], k_tol) << i;
}

TEST(Adam, L2OnlyOnItsRange) {
    // A zero gradient leaves a parameter where it is unless L2 pulls it towards 0.
    OptimizerConfig c = test_config();
    std::vector<float> w(8, 1.0f), g(8, 0.0f);
    Adam adam(c, 8, 2, 5);
    adam.step(w.data(), g.data());
    for (int i = 0; i < 8; ++i) {
        if (i >= 2 && i < 5)
            EXPECT_NEAR(w[i], 1.0 - 0.1, k_tol) << i;  // first step: lr * sign(l2 * w)
        else
            EXPECT_EQ(w[i], 1.0f) << i;
    }
}

TEST(Adam, LearningRateSchedule) {
    OptimizerConfig c;  // 1e-2, decay from step 20000 every 10000 steps by 0.33
    EXPECT_FLOAT_EQ(learning_rate_at(c, 0), 1e-2f);
    EXPECT_FLOAT_EQ(learning_rate_at(c, 19999), 1e-2f);
    EXPECT_FLOAT_EQ(learning_rate_at(c, 20000), 1e-2f * 0.33f);
    EXPECT_FLOAT_EQ(learning_rate_at(c, 29999), 1e-2f * 0.33f);
    EXPECT_FLOAT_EQ(learning_rate_at(c, 30000), float(1e-2 * 0.33 * 0.33));
    EXPECT_FLOAT_EQ(learning_rate_at(c, 45000), float(1e-2 * 0.33 * 0.33 * 0.33));
}

TEST(Adam, AverageEqualsParamsAfterOneStepAndBeforeAny) {
    Adam adam(test_config(), 4, 0, 4);
    std::vector<float> w = k_start, avg(4);
    adam.averaged_params(w.data(), avg.data());
    EXPECT_EQ(avg, w);
    adam.step(w.data(), k_grads[0]);
    adam.averaged_params(w.data(), avg.data());
    for (int i = 0; i < 4; ++i) EXPECT_FLOAT_EQ(avg[i], w[i]) << i;
}

TEST(Adam, NonFiniteGradientThrowsAndChangesNothing) {
    for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        Adam adam(test_config(), 4, 1, 3);
        std::vector<float> w = k_start;
        adam.step(w.data(), k_grads[0]);
        const std::vector<float> w_before = w;
        const AdamState state_before = adam.state();
        const float g[4] = {0.1f, 0.2f, bad, 0.3f};
        test::expect_error_message([&] { adam.step(w.data(), g); },
                                   {"gradient", "parameter 2", "not finite"});
        EXPECT_EQ(w, w_before);
        EXPECT_EQ(adam.state().m, state_before.m);
        EXPECT_EQ(adam.state().v, state_before.v);
        EXPECT_EQ(adam.state().ema, state_before.ema);
        EXPECT_EQ(adam.state().step, 1u);
    }
}

TEST(Adam, ResumeIsExact) {
    // Two steps, or one step, a state copy into a fresh optimizer and one more step: the same bits.
    Adam a(test_config(), 4, 1, 3);
    std::vector<float> wa = k_start;
    a.step(wa.data(), k_grads[0]);
    std::vector<float> wb = wa;
    Adam b(test_config(), 4, 1, 3);
    b.set_state(a.state());
    a.step(wa.data(), k_grads[1]);
    b.step(wb.data(), k_grads[1]);
    EXPECT_EQ(wa, wb);
    EXPECT_EQ(a.state().ema, b.state().ema);
}

TEST(Adam, SetStateSizeMismatch) {
    Adam adam(test_config(), 4, 0, 4);
    AdamState s = adam.state();
    s.v.resize(3);
    test::expect_error_message([&] { adam.set_state(s); }, {"'v'", "3 values", "4 parameters"});
    EXPECT_EQ(adam.state().v.size(), 4u);
}

TEST(Adam, ManyBlocksMatchOneParameterAtATime) {
    // Spread over many TBB blocks, every parameter (block edges and L2 range edges included) ends exactly
    // where an optimizer of that one parameter puts it.
    const size_t n = 300000, l2_begin = 1000, l2_end = 200000;
    std::vector<float> g(n), w(n, 0.5f);
    for (size_t i = 0; i < n; ++i) g[i] = std::sin(float(i)) * 0.01f;
    Adam adam(test_config(), n, l2_begin, l2_end);
    for (int s = 0; s < 3; ++s) adam.step(w.data(), g.data());
    for (size_t i : {size_t(0), size_t(999), size_t(1000), size_t(16383), size_t(16384), size_t(199999),
                     size_t(200000), n - 1}) {
        const bool l2 = i >= l2_begin && i < l2_end;
        Adam one(test_config(), 1, 0, l2 ? 1 : 0);
        float wi = 0.5f;
        for (int s = 0; s < 3; ++s) one.step(&wi, &g[i]);
        EXPECT_EQ(w[i], wi) << i;
    }
}

// The sparse step's reference: every parameter visited every step, in double; in the sparse range a zero
// gradient skips m, v and w (not the average).
struct DenseReference {
    OptimizerConfig cfg;
    size_t l2_begin, l2_end, sparse_begin;
    std::vector<double> w, m, v, ema;
    uint64_t step = 0;
    void apply(const std::vector<float>& g) {
        const double t = double(step + 1);
        const double c1 = 1.0 / (1.0 - std::pow(double(cfg.beta1), t)), c2 = 1.0 / (1.0 - std::pow(double(cfg.beta2), t));
        const double lr = learning_rate_at(cfg, step);
        for (size_t i = 0; i < w.size(); ++i) {
            double gi = g[i];
            if (i >= sparse_begin && gi == 0.0) {
                ema[i] = cfg.ema_decay * ema[i] + (1.0 - cfg.ema_decay) * w[i];
                continue;
            }
            if (i >= l2_begin && i < l2_end) gi += cfg.l2_reg * w[i];
            m[i] = cfg.beta1 * m[i] + (1.0 - cfg.beta1) * gi;
            v[i] = cfg.beta2 * v[i] + (1.0 - cfg.beta2) * gi * gi;
            w[i] -= lr * (m[i] * c1) / (std::sqrt(v[i] * c2) + cfg.epsilon);
            ema[i] = cfg.ema_decay * ema[i] + (1.0 - cfg.ema_decay) * w[i];
        }
        ++step;
    }
};

// Gradients for step s: the four dense parameters always; of the sparse entries (two features each) about a
// third reached, some of those with one or both features exactly zero (a corner of zero weight).
std::vector<float> sparse_test_gradient(int s, size_t n, size_t sparse_begin, std::vector<uint8_t>& reached) {
    std::vector<float> g(n, 0.0f);
    for (size_t i = 0; i < sparse_begin; ++i) g[i] = 0.1f * std::sin(float(i + 7 * s));
    for (size_t e = 0; e < reached.size(); ++e) {
        const uint32_t h = uint32_t(e * 2654435761u) ^ uint32_t(s * 40503u);
        if (h % 3 != 0) continue;
        reached[e] = 1;
        for (size_t f = 0; f < 2; ++f)
            if ((h >> (4 + f)) % 5 != 0) g[sparse_begin + 2 * e + f] = 0.01f * std::cos(float(e + 3 * f + s));
    }
    return g;
}

TEST(Adam, SparseStepsMatchTheDenseRuleOfTinyCudaNn) {
    // 4 MLP parameters (L2 on [1, 3)) and 40 000 entries of 2 (several TBB blocks); 12 steps through a
    // learning-rate decay. Parameters and moments follow the same float arithmetic as a dense step, so they
    // match the double reference to float rounding; the average is brought up to date lazily (ema_decay^k in
    // one multiplication instead of k), which agrees to a few float ulps of its order-1 values.
    OptimizerConfig cfg = test_config();
    cfg.decay_start = 6;
    cfg.decay_interval = 3;
    const size_t sparse_begin = 4, entries = 40000, n = sparse_begin + 2 * entries;
    Adam adam(cfg, n, 1, 3);
    DenseReference ref{cfg, 1, 3, sparse_begin, {}, std::vector<double>(n, 0.0), std::vector<double>(n, 0.0),
                       std::vector<double>(n, 0.0)};
    std::vector<float> w(n);
    for (size_t i = 0; i < n; ++i) w[i] = 0.5f * std::sin(float(i));
    ref.w.assign(w.begin(), w.end());
    std::vector<uint8_t> reached(entries, 0);
    for (int s = 0; s < 12; ++s) {
        std::vector<float> g = sparse_test_gradient(s, n, sparse_begin, reached);
        ref.apply(g);
        adam.step_sparse(w.data(), g.data(), SparseEntries{sparse_begin, 2, reached.data()});
        // The step hands back a zero gradient and no flags, ready for the next accumulation.
        for (size_t i = sparse_begin; i < n; ++i) ASSERT_EQ(g[i], 0.0f) << "step " << s << ", parameter " << i;
        for (size_t e = 0; e < entries; ++e) ASSERT_EQ(reached[e], 0) << "step " << s << ", entry " << e;
    }
    EXPECT_EQ(adam.steps(), 12u);
    std::vector<float> avg(n);
    adam.averaged_params(w.data(), avg.data());
    const double scale = 1.0 / (1.0 - std::pow(double(cfg.ema_decay), 12.0));
    size_t never_moved = 0;
    for (size_t i = 0; i < n; ++i) {
        ASSERT_NEAR(w[i], ref.w[i], 1e-6) << i;
        ASSERT_NEAR(avg[i], ref.ema[i] * scale, 2e-6) << i;
        never_moved += i >= sparse_begin && w[i] == float(0.5f * std::sin(float(i)));
    }
    EXPECT_GT(never_moved, 1000u) << "some sparse parameters were never reached with a gradient";
    // sync_ema makes the stored averages the dense ones (what a model file keeps).
    adam.sync_ema(w.data());
    for (size_t i = 0; i < n; ++i) ASSERT_NEAR(adam.state().ema[i], ref.ema[i], 2e-6) << i;
}

TEST(Adam, SparseResumeAndDenseStepsContinueTheSameRun) {
    // Sparse steps, the state saved (after sync_ema) into a fresh optimizer, more sparse steps: the same
    // parameters bit for bit as the optimizer that went on; a dense step after sparse ones updates every
    // average as if each had been kept every step.
    const size_t sparse_begin = 4, entries = 5000, n = sparse_begin + 2 * entries;
    std::vector<float> wa(n, 0.25f);
    Adam a(test_config(), n, 1, 3);
    std::vector<uint8_t> reached(entries, 0);
    for (int s = 0; s < 3; ++s) {
        std::vector<float> g = sparse_test_gradient(s, n, sparse_begin, reached);
        a.step_sparse(wa.data(), g.data(), SparseEntries{sparse_begin, 2, reached.data()});
    }
    a.sync_ema(wa.data());
    Adam b(test_config(), n, 1, 3);
    b.set_state(a.state());
    std::vector<float> wb = wa;
    for (int s = 3; s < 6; ++s) {
        std::vector<float> g = sparse_test_gradient(s, n, sparse_begin, reached);
        std::vector<uint8_t> reached_b = reached;
        std::vector<float> gb = g;
        a.step_sparse(wa.data(), g.data(), SparseEntries{sparse_begin, 2, reached.data()});
        b.step_sparse(wb.data(), gb.data(), SparseEntries{sparse_begin, 2, reached_b.data()});
    }
    EXPECT_EQ(wa, wb);
    std::vector<float> avg_a(n), avg_b(n);
    a.averaged_params(wa.data(), avg_a.data());
    b.averaged_params(wb.data(), avg_b.data());
    EXPECT_EQ(avg_a, avg_b);
    // A dense step after sparse ones: every average takes this step's parameters, from the caught-up value.
    std::vector<float> zero(n, 0.0f);
    a.sync_ema(wa.data());
    const std::vector<float> ema_before = a.state().ema;
    a.step(wa.data(), zero.data());
    for (size_t i : {size_t(5), size_t(777), n - 1})
        EXPECT_NEAR(a.state().ema[i], 0.95 * ema_before[i] + 0.05 * wa[i], 1e-6) << i;
}

TEST(Adam, SparseNonFiniteGradientThrowsAndChangesNothing) {
    const size_t sparse_begin = 4, entries = 100, n = sparse_begin + 2 * entries;
    Adam adam(test_config(), n, 1, 3);
    std::vector<float> w(n, 0.5f), g(n, 0.0f);
    std::vector<uint8_t> reached(entries, 0);
    reached[10] = reached[60] = 1;
    g[sparse_begin + 2 * 10] = 0.1f;
    g[sparse_begin + 2 * 60 + 1] = std::numeric_limits<float>::quiet_NaN();
    const std::vector<float> w_before = w;
    test::expect_error_message(
        [&] { adam.step_sparse(w.data(), g.data(), SparseEntries{sparse_begin, 2, reached.data()}); },
        {"gradient", "parameter " + std::to_string(sparse_begin + 2 * 60 + 1), "not finite"});
    EXPECT_EQ(w, w_before);
    EXPECT_EQ(adam.steps(), 0u);
    EXPECT_EQ(reached[10], 1);  // nothing was consumed either
    // A range that does not divide into entries, or that overlaps the L2 range, is refused.
    test::expect_error_message(
        [&] { adam.step_sparse(w.data(), g.data(), SparseEntries{sparse_begin + 1, 2, reached.data()}); },
        {"sparse range", "does not divide"});
    test::expect_error_message(
        [&] { adam.step_sparse(w.data(), g.data(), SparseEntries{2, 2, reached.data()}); }, {"sparse range"});
}

}  // namespace
}  // namespace npt::nerf
