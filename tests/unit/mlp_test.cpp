// The batched MLP (nerf/mlp_batch.h): forward against the per-sample NPT_HD mlp_forward, and backward against
// central finite differences of a float64 reference of the same network.
#include "nerf/mlp.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "nerf/mlp_batch.h"

namespace npt::nerf {
namespace {

constexpr double k_u_float = 0x1p-24;   // unit roundoff of float32
constexpr double k_u_double = 0x1p-53;  // and of float64

double gamma(double k, double u) { return k * u / (1.0 - k * u); }

// The two networks of the NeRF: density (hash features -> 64 -> 16) and colour (16 density features + 16 SH
// coefficients -> 64 -> 64 -> RGB).
constexpr MlpShape k_density{32, 64, 1, 16};
constexpr MlpShape k_colour{32, 64, 2, 3};

// The float64 network, evaluated on weights and inputs that are float32 values, so that it computes the exact
// function the float code approximates. With `masks` given, every ReLU uses those (1 = pass) instead of the
// sign of its own pre-activation: run on |W|, |x| with the real masks, it gives the magnitudes that bound the
// rounding error of the float code.
struct RefNet {
    std::vector<std::vector<double>> pre;   // [layer][sample * outputs + o], before the ReLU
    std::vector<std::vector<double>> post;  // after it (the last layer is linear)
};

RefNet ref_forward(const MlpShape& s, const std::vector<double>& w, const std::vector<double>& x, size_t n,
                   const RefNet* masks = nullptr) {
    RefNet r;
    const std::vector<double>* in = &x;
    for (int l = 0; l < s.layer_count(); ++l) {
        const int ni = s.layer_inputs(l), no = s.layer_outputs(l);
        const double* wl = w.data() + s.layer_offset(l);
        std::vector<double> z(n * no), a(n * no);
        for (size_t i = 0; i < n; ++i)
            for (int o = 0; o < no; ++o) {
                double acc = 0.0;
                for (int k = 0; k < ni; ++k) acc += wl[o * ni + k] * (*in)[i * ni + k];
                z[i * no + o] = acc;
                const bool last = l == s.hidden_layers;
                const bool pass = last || (masks ? masks->pre[l][i * no + o] > 0.0 : acc > 0.0);
                a[i * no + o] = pass ? acc : 0.0;
            }
        r.pre.push_back(std::move(z));
        r.post.push_back(std::move(a));
        in = &r.post.back();
    }
    return r;
}

// Gradients of sum(d_out * output) w.r.t. the weights and the input, with the ReLU masks of `masks`.
void ref_backward(const MlpShape& s, const std::vector<double>& w, const std::vector<double>& x, size_t n,
                  const RefNet& fwd, const RefNet& masks, const std::vector<double>& d_out,
                  std::vector<double>& d_w, std::vector<double>& d_x) {
    d_w.assign(s.param_count(), 0.0);
    std::vector<double> g = d_out;
    for (int l = s.hidden_layers; l >= 0; --l) {
        const int ni = s.layer_inputs(l), no = s.layer_outputs(l);
        const std::vector<double>& xin = l == 0 ? x : fwd.post[l - 1];
        const double* wl = w.data() + s.layer_offset(l);
        double* dwl = d_w.data() + s.layer_offset(l);
        std::vector<double> dx(n * ni, 0.0);
        for (size_t i = 0; i < n; ++i)
            for (int o = 0; o < no; ++o)
                for (int k = 0; k < ni; ++k) {
                    dwl[o * ni + k] += g[i * no + o] * xin[i * ni + k];
                    dx[i * ni + k] += g[i * no + o] * wl[o * ni + k];
                }
        if (l > 0)
            for (size_t j = 0; j < dx.size(); ++j)
                if (!(masks.pre[l - 1][j] > 0.0)) dx[j] = 0.0;
        g = std::move(dx);
    }
    d_x = std::move(g);
}

double loss(const RefNet& r, const std::vector<double>& d_out) {
    double sum = 0.0;
    for (size_t j = 0; j < d_out.size(); ++j) sum += d_out[j] * r.post.back()[j];
    return sum;
}

std::vector<double> to_double(const std::vector<float>& v) { return {v.begin(), v.end()}; }
std::vector<double> abs_of(std::vector<double> v) {
    for (double& x : v) x = std::abs(x);
    return v;
}

// He-style uniform weights, so that activations stay O(1) through the layers.
std::vector<float> random_weights(const MlpShape& s, std::mt19937& rng) {
    std::vector<float> w(s.param_count());
    for (int l = 0; l < s.layer_count(); ++l) {
        const float bound = std::sqrt(6.0f / float(s.layer_inputs(l)));
        std::uniform_real_distribution<float> u(-bound, bound);
        for (size_t i = s.layer_offset(l); i < s.layer_offset(l + 1); ++i) w[i] = u(rng);
    }
    return w;
}

// n input samples whose every pre-activation is at least `margin` away from the ReLU kink in the exact
// network, so that neither float rounding nor a finite-difference step can flip a ReLU. Samples that come
// closer are drawn again.
std::vector<float> samples_away_from_kinks(const MlpShape& s, const std::vector<float>& w, size_t n,
                                           double margin, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const std::vector<double> wd = to_double(w);
    std::vector<float> x;
    int draws = 0;
    while (x.size() < n * size_t(s.inputs)) {
        std::vector<float> sample(s.inputs);
        for (float& v : sample) v = u(rng);
        const RefNet r = ref_forward(s, wd, to_double(sample), 1);
        bool ok = true;
        for (int l = 0; l < s.hidden_layers; ++l)
            for (double z : r.pre[l]) ok = ok && std::abs(z) >= margin;
        if (ok) x.insert(x.end(), sample.begin(), sample.end());
        EXPECT_LT(++draws, 1000) << "cannot find samples away from the ReLU kinks";
        if (draws >= 1000) break;
    }
    return x;
}

TEST(MlpBatch, ForwardMatchesPerSampleForward) {
    for (const MlpShape& s : {k_density, k_colour}) {
        std::mt19937 rng(3);
        const size_t n = 1001;  // not a multiple of any block of the matmul
        const std::vector<float> w = random_weights(s, rng);
        std::vector<float> x(n * s.inputs);
        std::uniform_real_distribution<float> u(-1.0f, 1.0f);
        for (float& v : x) v = u(rng);

        std::vector<float> out(n * s.outputs), out_kept(n * s.outputs);
        mlp_forward_batch(s, w.data(), x.data(), n, out.data(), nullptr);
        MlpActivations acts;
        mlp_forward_batch(s, w.data(), x.data(), n, out_kept.data(), &acts);
        EXPECT_EQ(acts.n, n);
        ASSERT_EQ(acts.layer_outputs.size(), n * size_t(s.width * s.hidden_layers + s.outputs));
        // Same products in the same order: keeping the activations must not change a bit.
        EXPECT_EQ(out, out_kept);
        for (size_t j = 0; j < out.size(); ++j) ASSERT_EQ(acts.output(s)[j], out[j]);

        // Both codes compute each output by float dot products chained through the layers; each is within
        // gamma_K (K = the sum of the layers' input counts) of the exact value, relative to the output of the
        // same network on |W|, |x| (Higham 3.1 applied layer by layer), so they differ by at most twice that.
        const std::vector<double> xd = to_double(x), wd = to_double(w);
        const RefNet exact = ref_forward(s, wd, xd, n);
        const RefNet magnitude = ref_forward(s, abs_of(wd), abs_of(xd), n, &exact);
        int k_sum = 0;
        for (int l = 0; l < s.layer_count(); ++l) k_sum += s.layer_inputs(l);
        const double g = gamma(k_sum + 1, k_u_float);
        for (size_t i = 0; i < n; ++i) {
            float one[k_max_mlp_width];
            mlp_forward(s, w.data(), x.data() + i * s.inputs, one);
            for (int o = 0; o < s.outputs; ++o) {
                const size_t j = i * s.outputs + o;
                ASSERT_LE(std::abs(double(one[o]) - double(out[j])), 2.0 * g * magnitude.post.back()[j])
                    << "sample " << i << " output " << o;
            }
        }
    }
}

// Central differences of the float64 loss sum(d_out * output) against the float32 backward pass, for every
// weight of every layer and every input.
//
// Error budget:
// - The finite difference: the samples keep every pre-activation at least k_margin from a ReLU kink, and one
//   step of size k_step moves a pre-activation by at most k_step * |d pre / d param| (< 100 * k_step here),
//   so no ReLU flips (checked below). The loss is then exactly linear in each single parameter (the network
//   is linear between kinks), the central difference has no truncation error, and only the rounding of the
//   two float64 losses remains: each within gamma_Kd * L_abs (L_abs = the loss of the |.| network, Kd its
//   longest chain of sums), so the difference quotient is within gamma_Kd * L_abs / k_step.
// - The float32 backward: every gradient entry is a chain of float dot products (forward through the layers,
//   back through them, then the sum over samples), so it is within gamma_K of the exact value relative to the
//   same gradient of the |.| network (Higham 3.1 per product, first order), K = sum of the dot lengths.
// The tolerance is the sum of the two.
void check_gradients(const MlpShape& s, size_t n, unsigned seed) {
    constexpr double k_margin = 1e-2;
    constexpr double k_step = 1e-4;
    std::mt19937 rng(seed);
    const std::vector<float> w = random_weights(s, rng);
    const std::vector<float> x = samples_away_from_kinks(s, w, n, k_margin, rng);
    ASSERT_EQ(x.size(), n * s.inputs);
    std::vector<float> d_out(n * s.outputs);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (float& v : d_out) v = u(rng);

    // The code under test.
    std::vector<float> out(n * s.outputs), d_w(s.param_count(), 0.0f), d_x(n * s.inputs, -1.0f);
    MlpActivations acts;
    mlp_forward_batch(s, w.data(), x.data(), n, out.data(), &acts);
    mlp_backward_batch(s, w.data(), x.data(), acts, d_out.data(), d_w.data(), d_x.data());

    const std::vector<double> wd = to_double(w), xd = to_double(x), dod = to_double(d_out);
    const RefNet exact = ref_forward(s, wd, xd, n);
    const RefNet mag = ref_forward(s, abs_of(wd), abs_of(xd), n, &exact);
    std::vector<double> mag_dw, mag_dx;
    ref_backward(s, abs_of(wd), abs_of(xd), n, mag, exact, abs_of(dod), mag_dw, mag_dx);
    const double loss_abs = loss(mag, abs_of(dod));

    int chain = int(n);  // the sum over samples of a weight gradient
    for (int l = 0; l < s.layer_count(); ++l) chain += s.layer_inputs(l) + s.layer_outputs(l);
    const double g_float = gamma(chain + 2, k_u_float);
    const double g_double = gamma(chain + 2 + int(n * s.outputs), k_u_double);  // + the loss sum
    const double fd_error = 2.0 * g_double * loss_abs / (2.0 * k_step);

    // Loss with one parameter moved, and whether every ReLU kept its side.
    auto moved_loss = [&](std::vector<double> wv, std::vector<double> xv, bool weight, size_t index,
                          double delta) {
        (weight ? wv : xv)[index] += delta;
        const RefNet r = ref_forward(s, wv, xv, n);
        for (int l = 0; l < s.hidden_layers; ++l)
            for (size_t j = 0; j < r.pre[l].size(); ++j)
                EXPECT_EQ(r.pre[l][j] > 0.0, exact.pre[l][j] > 0.0)
                    << "a finite-difference step crossed a kink";
        return loss(r, dod);
    };

    double worst = 0.0;  // largest error as a fraction of its tolerance, reported for the record
    for (int l = 0; l < s.layer_count(); ++l) {
        SCOPED_TRACE("layer " + std::to_string(l));
        int failures = 0;
        for (size_t i = s.layer_offset(l); i < s.layer_offset(l + 1) && failures < 3; ++i) {
            const double fd =
                (moved_loss(wd, xd, true, i, k_step) - moved_loss(wd, xd, true, i, -k_step)) / (2.0 * k_step);
            const double tol = g_float * mag_dw[i] + fd_error;
            worst = std::max(worst, std::abs(d_w[i] - fd) / tol);
            if (!(std::abs(d_w[i] - fd) <= tol)) {
                ++failures;
                ADD_FAILURE() << "dW[" << i << "] = " << d_w[i] << ", finite difference " << fd << ", tol "
                              << tol;
            }
        }
    }
    int failures = 0;
    for (size_t i = 0; i < xd.size() && failures < 3; ++i) {
        const double fd =
            (moved_loss(wd, xd, false, i, k_step) - moved_loss(wd, xd, false, i, -k_step)) / (2.0 * k_step);
        const double tol = g_float * mag_dx[i] + fd_error;
        worst = std::max(worst, std::abs(d_x[i] - fd) / tol);
        if (!(std::abs(d_x[i] - fd) <= tol)) {
            ++failures;
            ADD_FAILURE() << "d_in[" << i << "] = " << d_x[i] << ", finite difference " << fd << ", tol "
                          << tol;
        }
    }
    std::printf("inputs %d, width %d, hidden %d, outputs %d, %zu samples: worst error %.3f of its bound\n",
                s.inputs, s.width, s.hidden_layers, s.outputs, n, worst);
}

TEST(MlpBatch, GradientsMatchFiniteDifferencesDensityNetwork) { check_gradients(k_density, 13, 5); }
TEST(MlpBatch, GradientsMatchFiniteDifferencesColourNetwork) { check_gradients(k_colour, 13, 6); }

TEST(MlpBatch, BackwardAddsWeightGradientsAndInputGradientIsOptional) {
    const MlpShape s = k_colour;
    std::mt19937 rng(9);
    const size_t n = 40;
    const std::vector<float> w = random_weights(s, rng);
    std::vector<float> x(n * s.inputs), d_out(n * s.outputs), out(n * s.outputs);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (float& v : x) v = u(rng);
    for (float& v : d_out) v = u(rng);
    MlpActivations acts;
    mlp_forward_batch(s, w.data(), x.data(), n, out.data(), &acts);

    std::vector<float> fresh(s.param_count(), 0.0f), d_x(n * s.inputs);
    mlp_backward_batch(s, w.data(), x.data(), acts, d_out.data(), fresh.data(), d_x.data());
    // Starting from 0.25 instead of 0, each entry is 0.25 + g rounded once more (or a few times, one per
    // depth block of the matmul): within 2 u (0.25 + |g|) of 0.25 + the fresh g.
    std::vector<float> added(s.param_count(), 0.25f);
    mlp_backward_batch(s, w.data(), x.data(), acts, d_out.data(), added.data(), nullptr);
    for (size_t i = 0; i < fresh.size(); ++i)
        ASSERT_NEAR(added[i], 0.25 + double(fresh[i]), 2.0 * k_u_float * (0.25 + std::abs(fresh[i])))
            << "dW[" << i << "]";
}

}  // namespace
}  // namespace npt::nerf
