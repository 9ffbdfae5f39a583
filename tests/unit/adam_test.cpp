// Adam: one and three steps against values worked out from the formulas in double (L2 on a sub-range, a
// learning-rate decay inside the three steps), the decay schedule, the EMA's bias correction, and the errors.
#include "nerf/adam.h"

#include <gtest/gtest.h>

#include <cmath>
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

}  // namespace
}  // namespace npt::nerf
