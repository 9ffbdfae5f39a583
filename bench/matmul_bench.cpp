// Our matmul (both kernel builds) against Eigen 3 on the products of NeRF MLP training, one thread, batch n =
// 4096: forward Y = X W^T, backward dX = dY W, weight gradient dW += dY^T X, for each layer shape of the
// density and colour networks. Prints GFLOP/s (best of several timed repeats). This file is built with -mavx2
// -mfma so that Eigen uses the same instruction set as our AVX2 kernel. The numbers go into the header of
// nerf/matmul.cpp.
#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <random>
#include <vector>

#include "nerf/matmul.h"
#include "nerf/matmul_kernels.h"

namespace {

using RowMajor = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using Map = Eigen::Map<RowMajor>;
using ConstMap = Eigen::Map<const RowMajor>;

constexpr int k_batch = 4096;
constexpr double k_min_seconds = 0.05;  // per timed repeat: long enough to dwarf the timer
constexpr int k_repeats = 7;

// Best GFLOP/s over k_repeats timed runs of `fn`, each repeated until it takes k_min_seconds.
double gflops(double flops, const std::function<void()>& fn) {
    fn();  // warm caches and the page tables
    int iters = 1;
    for (;;) {
        const auto t0 = std::chrono::steady_clock::now();
        for (int i = 0; i < iters; ++i) fn();
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (s >= k_min_seconds) break;
        iters *= 2;
    }
    double best = 0.0;
    for (int r = 0; r < k_repeats; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        for (int i = 0; i < iters; ++i) fn();
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        best = std::max(best, flops * iters / s * 1e-9);
    }
    return best;
}

std::vector<float> random_vector(size_t size, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<float> v(size);
    for (float& x : v) x = u(rng);
    return v;
}

}  // namespace

int main() {
    using npt::nerf::matmul;
    using GenericFn = decltype(&npt::nerf::generic::matmul);
    const GenericFn generic = &npt::nerf::generic::matmul;
    std::printf(
        "matmul_bench: one thread, batch n = %d, dispatched kernel '%s', Eigen %d.%d.%d; GFLOP/s, best of "
        "%d\n",
        k_batch, npt::nerf::matmul_kernel_name(), EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION,
        EIGEN_MINOR_VERSION, k_repeats);
    std::printf("%-8s %-10s %-30s %8s %8s %8s %7s\n", "layer", "product", "shape (m x n x k)", "ours",
                "generic", "eigen", "ours/eigen");
    const int shapes[][2] = {{32, 64}, {64, 64}, {64, 16}, {64, 3}};  // (in, out) of the NeRF's layers
    std::mt19937 rng(1);
    const int n = k_batch;
    for (const auto& sh : shapes) {
        const int in = sh[0], out = sh[1];
        const auto x = random_vector(size_t(n) * in, rng);
        const auto w = random_vector(size_t(out) * in, rng);
        const auto dy = random_vector(size_t(n) * out, rng);
        std::vector<float> y(size_t(n) * out), dx(size_t(n) * in), dw(size_t(out) * in);
        const ConstMap xm(x.data(), n, in), wm(w.data(), out, in), dym(dy.data(), n, out);
        Map ym(y.data(), n, out), dxm(dx.data(), n, in), dwm(dw.data(), out, in);
        const double flops = 2.0 * n * in * out;
        char layer[16], shape[64];
        std::snprintf(layer, sizeof layer, "%d->%d", in, out);

        struct Row {
            const char* name;
            int m, nn, k;
            std::function<void(GenericFn)> ours;
            std::function<void()> eigen;
        };
        const Row rows[] = {
            {"Y=XW^T", n, out, in,
             [&](GenericFn f) {
                 f(n, out, in, x.data(), in, false, w.data(), in, true, y.data(), out, false);
             },
             [&] { ym.noalias() = xm * wm.transpose(); }},
            {"dX=dYW", n, in, out,
             [&](GenericFn f) {
                 f(n, in, out, dy.data(), out, false, w.data(), in, false, dx.data(), in, false);
             },
             [&] { dxm.noalias() = dym * wm; }},
            {"dW+=dY^TX", out, in, n,
             [&](GenericFn f) {
                 f(out, in, n, dy.data(), out, true, x.data(), in, false, dw.data(), in, true);
             },
             [&] { dwm.noalias() += dym.transpose() * xm; }},
        };
        for (const Row& r : rows) {
            const double ours = gflops(flops, [&] { r.ours(&matmul); });
            const double gen = gflops(flops, [&] { r.ours(generic); });
            const double eig = gflops(flops, r.eigen);
            std::snprintf(shape, sizeof shape, "%d x %d x %d", r.m, r.nn, r.k);
            std::printf("%-8s %-10s %-30s %8.1f %8.1f %8.1f %7.2f\n", layer, r.name, shape, ours, gen, eig,
                        ours / eig);
        }
    }
    return 0;
}
