// matmul (nerf/matmul.h) against a naive double-precision product, for every kernel build this CPU can run.
#include "nerf/matmul.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "nerf/matmul_kernels.h"

namespace npt::nerf {
namespace {

using MatmulFn = void (*)(int, int, int, const float*, int, bool, const float*, int, bool, float*, int, bool);

struct KernelCase {
    const char* name;
    MatmulFn fn;
    bool runnable;
};

bool cpu_has_avx2_fma() {
#if defined(__x86_64__) || defined(__i386__)
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
    return false;
#endif
}

// Both builds; the dispatched matmul is one of them (MatmulDispatchesToTheBuildItNames).
std::vector<KernelCase> kernels() {
    return {{"generic", &generic::matmul, true}, {"avx2", &avx2::matmul, cpu_has_avx2_fma()}};
}

constexpr double k_unit_roundoff = 0x1p-24;  // float32

// Runs one product with leading dimensions padded past the widths (so strides are tested, not just shapes),
// and compares every element with the double-precision product. Any order of float summation of k products
// onto c0 is within gamma_{k+1} = (k+1) u / (1 - (k+1) u) of the exact value, relative to
// |c0| + sum |a_ip b_pj| (Higham, Accuracy and Stability, 3.1); that bound is the tolerance. Returns the
// number of elements that failed, so that a caller can stop after the first failing shape.
int check_product(MatmulFn fn, int m, int n, int k, bool ta, bool tb, bool acc, std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const int a_rows = ta ? k : m, a_cols = ta ? m : k;
    const int b_rows = tb ? n : k, b_cols = tb ? k : n;
    const int lda = a_cols + 3, ldb = b_cols + 5, ldc = n + 2;
    std::vector<float> a(size_t(a_rows) * lda), b(size_t(b_rows) * ldb), c(size_t(m) * ldc);
    for (float& x : a) x = u(rng);
    for (float& x : b) x = u(rng);
    for (float& x : c) x = u(rng);
    const std::vector<float> c0 = c;
    fn(m, n, k, a.data(), lda, ta, b.data(), ldb, tb, c.data(), ldc, acc);

    const double gamma = (k + 1) * k_unit_roundoff / (1.0 - (k + 1) * k_unit_roundoff);
    int failures = 0;
    for (int i = 0; i < m; ++i) {
        for (int j = 0; j < n; ++j) {
            double exact = acc ? c0[size_t(i) * ldc + j] : 0.0;
            double magnitude = std::abs(exact);
            for (int p = 0; p < k; ++p) {
                const double av = ta ? a[size_t(p) * lda + i] : a[size_t(i) * lda + p];
                const double bv = tb ? b[size_t(j) * ldb + p] : b[size_t(p) * ldb + j];
                exact += av * bv;
                magnitude += std::abs(av * bv);
            }
            const double got = c[size_t(i) * ldc + j];
            if (!(std::abs(got - exact) <= gamma * magnitude)) {
                if (failures++ < 3)
                    ADD_FAILURE() << "m=" << m << " n=" << n << " k=" << k << " ta=" << ta << " tb=" << tb
                                  << " acc=" << acc << ": C[" << i << "][" << j << "] = " << got << ", exact "
                                  << exact << ", bound " << gamma * magnitude;
            }
        }
        // The padding between rows of C is not C's: it must be untouched.
        for (int j = n; j < ldc; ++j)
            if (c[size_t(i) * ldc + j] != c0[size_t(i) * ldc + j]) {
                ++failures;
                ADD_FAILURE() << "m=" << m << " n=" << n << " k=" << k << ": wrote past row " << i;
            }
    }
    return failures;
}

TEST(Matmul, MatchesNaiveProductForAllTransposesAndOddSizes) {
    // Sizes around the micro-tile (6 x 8 or 16) and vector widths: 1, 3, one past 16, one short of and one
    // past 64, and over 96 (the row block).
    const int sizes[] = {1, 3, 17, 63, 65, 130};
    for (const KernelCase& kc : kernels()) {
        if (!kc.runnable) {
            std::printf("kernel %s: this CPU cannot run it, not tested\n", kc.name);
            continue;
        }
        SCOPED_TRACE(kc.name);
        std::mt19937 rng(7);
        int failures = 0;
        for (int m : sizes)
            for (int n : sizes)
                for (int k : sizes)
                    for (int flags = 0; flags < 8 && failures == 0; ++flags)
                        failures += check_product(kc.fn, m, n, k, flags & 1, flags & 2, flags & 4, rng);
        EXPECT_EQ(failures, 0);
    }
}

TEST(Matmul, CrossesEveryBlockBoundary) {
    // m over the 96-row block, n over the 256-column block, k over two 256-deep blocks (accumulation across
    // depth blocks), each just past the boundary so that the edge paths run too.
    for (const KernelCase& kc : kernels()) {
        if (!kc.runnable) continue;
        SCOPED_TRACE(kc.name);
        std::mt19937 rng(11);
        for (int flags = 0; flags < 8; ++flags)
            EXPECT_EQ(check_product(kc.fn, 100, 260, 520, flags & 1, flags & 2, flags & 4, rng), 0);
    }
}

TEST(Matmul, NerfTrainingShapes) {
    // The products of an MLP layer (in -> out) over a batch: forward Y = X W^T, backward dX = dY W and
    // dW += dY^T X, for the layer shapes of the density and colour networks.
    const int batch = 1031;  // not a multiple of any block size
    const int layers[][2] = {{32, 64}, {64, 16}, {64, 64}, {64, 3}};
    for (const KernelCase& kc : kernels()) {
        if (!kc.runnable) continue;
        SCOPED_TRACE(kc.name);
        std::mt19937 rng(13);
        for (const auto& l : layers) {
            const int in = l[0], out = l[1];
            EXPECT_EQ(check_product(kc.fn, batch, out, in, false, true, false, rng), 0);
            EXPECT_EQ(check_product(kc.fn, batch, in, out, false, false, false, rng), 0);
            EXPECT_EQ(check_product(kc.fn, out, in, batch, true, false, true, rng), 0);
        }
    }
}

TEST(Matmul, ZeroDepthClearsOrKeepsC) {
    for (const KernelCase& kc : kernels()) {
        if (!kc.runnable) continue;
        SCOPED_TRACE(kc.name);
        std::vector<float> c(12, 5.0f);
        kc.fn(3, 4, 0, nullptr, 1, false, nullptr, 4, false, c.data(), 4, true);
        for (float x : c) EXPECT_EQ(x, 5.0f);
        kc.fn(3, 4, 0, nullptr, 1, false, nullptr, 4, false, c.data(), 4, false);
        for (float x : c) EXPECT_EQ(x, 0.0f);
    }
}

TEST(Matmul, DispatchesToTheBuildItNames) {
    EXPECT_STREQ(matmul_kernel_name(), cpu_has_avx2_fma() ? "avx2-fma" : "generic");
    // Same arithmetic in the same order: the dispatched product is bit for bit the named build's.
    const MatmulFn named = cpu_has_avx2_fma() ? &avx2::matmul : &generic::matmul;
    std::mt19937 rng(17);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<float> a(70 * 33), b(33 * 19), c1(70 * 19), c2(70 * 19);
    for (float& x : a) x = u(rng);
    for (float& x : b) x = u(rng);
    matmul(70, 19, 33, a.data(), 33, false, b.data(), 19, false, c1.data(), 19, false);
    named(70, 19, 33, a.data(), 33, false, b.data(), 19, false, c2.data(), 19, false);
    EXPECT_EQ(c1, c2);
}

}  // namespace
}  // namespace npt::nerf
