// Single-threaded float32 matrix products for the MLPs, cache-blocked, with an AVX2+FMA build chosen at run
// time when the CPU has it (the rest of the library targets x86-64-v2).
#pragma once

namespace npt::nerf {

// C[m][n] = (accumulate ? C : 0) + op(A)[m][k] * op(B)[k][n]; all matrices row-major with leading dimensions
// (row strides) lda, ldb, ldc. op(X) = X, or X transposed when the flag says so (then A is stored [k][m],
// B [n][k]).
void matmul(int m, int n, int k, const float* a, int lda, bool transpose_a, const float* b, int ldb,
            bool transpose_b, float* c, int ldc, bool accumulate);

// Which kernel matmul uses on this CPU ("avx2-fma" or "generic"), for logs and benchmarks.
const char* matmul_kernel_name();

}  // namespace npt::nerf
