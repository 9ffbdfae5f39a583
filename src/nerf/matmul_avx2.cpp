// The AVX2+FMA build of the matmul kernel (matmul_kernel.inc). This file alone is compiled with -mavx2 -mfma
// (src/CMakeLists.txt); matmul.cpp calls it only on a CPU that has both.
#include <immintrin.h>

#include <cstddef>

#include "nerf/matmul_kernels.h"

namespace npt::nerf::avx2 {
namespace {

using V = __m256;
constexpr int k_lanes = 8;
inline V vload(const float* p) { return _mm256_loadu_ps(p); }
inline void vstore(float* p, V v) { _mm256_storeu_ps(p, v); }
inline V vbroadcast(float x) { return _mm256_set1_ps(x); }
inline V vmadd(V a, V b, V c) { return _mm256_fmadd_ps(a, b, c); }

#include "nerf/matmul_kernel.inc"

}  // namespace

void matmul(int m, int n, int k, const float* a, int lda, bool transpose_a, const float* b, int ldb,
            bool transpose_b, float* c, int ldc, bool accumulate) {
    matmul_impl(m, n, k, a, lda, transpose_a, b, ldb, transpose_b, c, ldc, accumulate);
}

}  // namespace npt::nerf::avx2
