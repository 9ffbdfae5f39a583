// The portable build of the matmul kernel (matmul_kernel.inc): 4-float SSE vectors, no FMA, for CPUs without
// AVX2+FMA. Compiled with the library's flags (x86-64-v2).
#include <immintrin.h>

#include <cstddef>

#include "nerf/matmul_kernels.h"

namespace npt::nerf::generic {
namespace {

using V = __m128;
constexpr int k_lanes = 4;
inline V vload(const float* p) { return _mm_loadu_ps(p); }
inline void vstore(float* p, V v) { _mm_storeu_ps(p, v); }
inline V vbroadcast(float x) { return _mm_set1_ps(x); }
inline V vmadd(V a, V b, V c) { return _mm_add_ps(_mm_mul_ps(a, b), c); }

#include "nerf/matmul_kernel.inc"

}  // namespace

void matmul(int m, int n, int k, const float* a, int lda, bool transpose_a, const float* b, int ldb,
            bool transpose_b, float* c, int ldc, bool accumulate) {
    matmul_impl(m, n, k, a, lda, transpose_a, b, ldb, transpose_b, c, ldc, accumulate);
}

}  // namespace npt::nerf::generic
