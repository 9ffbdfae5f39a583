// Chooses the matmul kernel for this CPU: the AVX2+FMA build of matmul_kernel.inc when the CPU has both, else
// the SSE build. Both builds are the same source, so they differ only in rounding (FMA) and speed.
//
// Why our own kernel and not Eigen 3.4 (Debian's libeigen3-dev; Map + noalias products): measured with
// bench/matmul_bench.cpp, both built with -mavx2 -mfma, one thread, batch n = 4096, AMD EPYC (2 cores,
// otherwise idle: load 0.3), GFLOP/s, best of 7:
//   layer    product     ours  eigen      layer    product     ours  eigen
//   32->64   Y=XW^T     123.4  105.7      64->16   Y=XW^T     122.9   87.0
//   32->64   dX=dYW     122.2   96.3      64->16   dX=dYW     120.7   99.6
//   32->64   dW+=dY^TX  116.8   85.0      64->16   dW+=dY^TX  110.4   83.5
//   64->64   Y=XW^T     123.8  110.6      64->3    Y=XW^T      32.6   25.8
//   64->64   dX=dYW     125.5  110.4      64->3    dX=dYW      67.6   50.6
//   64->64   dW+=dY^TX  105.1   99.3      64->3    dW+=dY^TX   78.9   25.3
// Ours is ahead in every case (1.06x to 3.1x; Eigen packs both operands whatever their shape, and pads the
// 3-wide ones), so Eigen is not used. The SSE build runs at 25-45. A rerun while other builds shared the two
// cores scattered both columns by up to 2x either way: compare runs on a quiet machine only.
#include "nerf/matmul.h"

#include "nerf/matmul_kernels.h"

namespace npt::nerf {
namespace {

using MatmulFn = void (*)(int, int, int, const float*, int, bool, const float*, int, bool, float*, int, bool);

struct Kernel {
    MatmulFn fn;
    const char* name;
};

Kernel choose_kernel() {
#if defined(__x86_64__) || defined(__i386__)
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return {&avx2::matmul, "avx2-fma"};
#endif
    return {&generic::matmul, "generic"};
}

// Chosen once; the CPU does not change under a running process.
const Kernel& kernel() {
    static const Kernel k = choose_kernel();
    return k;
}

}  // namespace

void matmul(int m, int n, int k, const float* a, int lda, bool transpose_a, const float* b, int ldb,
            bool transpose_b, float* c, int ldc, bool accumulate) {
    kernel().fn(m, n, k, a, lda, transpose_a, b, ldb, transpose_b, c, ldc, accumulate);
}

const char* matmul_kernel_name() { return kernel().name; }

}  // namespace npt::nerf
