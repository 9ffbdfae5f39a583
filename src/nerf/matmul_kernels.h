// The two builds of the matmul kernel that matmul.cpp chooses between; same arguments as npt::nerf::matmul.
// Only matmul.cpp and the tests include this.
#pragma once

namespace npt::nerf {

namespace avx2 {
// Needs a CPU with AVX2 and FMA.
void matmul(int m, int n, int k, const float* a, int lda, bool transpose_a, const float* b, int ldb,
            bool transpose_b, float* c, int ldc, bool accumulate);
}  // namespace avx2

namespace generic {
void matmul(int m, int n, int k, const float* a, int lda, bool transpose_a, const float* b, int ldb,
            bool transpose_b, float* c, int ldc, bool accumulate);
}  // namespace generic

}  // namespace npt::nerf
