// Fully fused NeRF MLPs on tensor cores (see fused_mlp.h). Layout of the work: a block of 8 warps takes a tile
// of 128 samples; warp w owns rows [16 w, 16 w + 16) of every activation buffer, so the forward and backward
// passes need no block barrier. Layer outputs go through a per-warp fp32 scratch tile (store_matrix_sync), so
// the element-to-(row, column) mapping of WMMA fragments never matters: each lane converts 8 known elements.
// The weight gradients reduce over all 128 rows, so they come after a barrier: 40 tiles of 16x16 spread over
// the 8 warps, accumulated in registers across every tile the (persistent) block processes, added to global
// memory once at the end.
#include "nerf/cuda/fused_mlp.h"

#include <mma.h>

#include <algorithm>

#include "core/cuda/device_buffer.h"
#include "nerf/sh_encoding.h"

namespace npt::nerf::cuda {

bool mlp_shape_supported(const NerfLayout& l, std::string* why) {
    auto fail = [&](const std::string& m) {
        if (why) *why = m;
        return false;
    };
    if (l.grid.output_dims() != k_mlp_inputs)
        return fail("the hash grid must give 32 features (levels x features_per_level), not " +
                    std::to_string(l.grid.output_dims()));
    if (l.density.width != 64 || l.density.hidden_layers != 1 || l.density.outputs != 16)
        return fail("the density MLP must be 1 hidden layer of 64 with 16 outputs");
    if (l.color.inputs != 32 || l.color.width != 64 || l.color.hidden_layers != 2 || l.color.outputs != 3)
        return fail("the colour MLP must be 2 hidden layers of 64 with 3 outputs");
    if (l.density_offset != 0 || l.color_offset != 3072 || l.grid_offset != size_t(k_mlp_param_count))
        return fail("unexpected parameter layout");
    return true;
}

namespace {

using namespace nvcuda;

constexpr int k_warps = 8;
constexpr int k_threads = 32 * k_warps;
constexpr int k_rows = k_mlp_rows_per_tile;
static_assert(k_rows == 16 * k_warps, "one 16-row slice per warp");

// Row strides of the shared-memory activation buffers, in halves: 8 more than the width, so that the 16
// rows a fragment load touches start in different banks. Multiples of 8 (WMMA's rule for 16-bit types).
constexpr int k_ld16 = 24, k_ld32 = 40, k_ld64 = 72;

// Offsets of the layers in the fp16 weight buffer (row-major [outputs][inputs]).
constexpr int k_w_d0 = 0;                  // density 0: [64][32]
constexpr int k_w_d1 = k_w_d0 + 64 * 32;   // density 1: [16][64]
constexpr int k_w_c0 = k_w_d1 + 16 * 64;   // colour 0:  [64][32]
constexpr int k_w_c1 = k_w_c0 + 64 * 32;   // colour 1:  [64][64]
constexpr int k_w_c2 = k_w_c1 + 64 * 64;   // colour 2:  [16][64], rows 3..15 zero
static_assert(k_w_c2 + 16 * 64 == k_mlp_half_weights, "weight buffer layout");

constexpr float k_half_max = 65504.0f;

using FragA = wmma::fragment<wmma::matrix_a, 16, 16, 16, __half, wmma::row_major>;
using FragAcc = wmma::fragment<wmma::accumulator, 16, 16, 16, float>;

__device__ __forceinline__ void store8(__half* dst, const float v[8]) {
    __align__(16) __half2 h[4];
#pragma unroll
    for (int j = 0; j < 4; ++j) h[j] = __floats2half2_rn(v[2 * j], v[2 * j + 1]);
    *reinterpret_cast<uint4*>(dst) = *reinterpret_cast<const uint4*>(h);
}

// Gradients may exceed fp16's range in rare cases: saturate instead of becoming infinite.
__device__ __forceinline__ void store8_saturated(__half* dst, float v[8]) {
#pragma unroll
    for (int j = 0; j < 8; ++j) v[j] = fminf(fmaxf(v[j], -k_half_max), k_half_max);
    store8(dst, v);
}

__device__ __forceinline__ void load8(const __half* src, float v[8]) {
    const uint4 u = *reinterpret_cast<const uint4*>(src);
    const __half2* h = reinterpret_cast<const __half2*>(&u);
#pragma unroll
    for (int j = 0; j < 4; ++j) {
        const float2 f = __half22float2(h[j]);
        v[2 * j] = f.x;
        v[2 * j + 1] = f.y;
    }
}

enum class Pass { forward, backward };

// out[16][16 n_tiles] = a[16][16 k_tiles] x B for the warp's 16 rows. Forward: B = W^T with W [out][in]
// row-major (ldw = in), i.e. y = W x per row; backward: B = W, i.e. dx = dy W. Each 16x16 result goes through
// the warp's fp32 scratch tile; epi(row, col, v) then gets 8 consecutive values of one row (row in [0,16),
// col the absolute first column).
template <Pass pass, int k_tiles, typename Epilogue>
__device__ __forceinline__ void warp_gemm(const __half* a, int lda, const __half* w, int ldw, int n_tiles,
                                          float* scratch, Epilogue&& epi) {
    const int lane = threadIdx.x & 31;
    for (int nt = 0; nt < n_tiles; ++nt) {
        FragAcc acc;
        wmma::fill_fragment(acc, 0.0f);
#pragma unroll
        for (int kt = 0; kt < k_tiles; ++kt) {
            FragA fa;
            wmma::load_matrix_sync(fa, a + kt * 16, lda);
            if constexpr (pass == Pass::forward) {
                wmma::fragment<wmma::matrix_b, 16, 16, 16, __half, wmma::col_major> fb;
                wmma::load_matrix_sync(fb, w + nt * 16 * ldw + kt * 16, ldw);
                wmma::mma_sync(acc, fa, fb, acc);
            } else {
                wmma::fragment<wmma::matrix_b, 16, 16, 16, __half, wmma::row_major> fb;
                wmma::load_matrix_sync(fb, w + kt * 16 * ldw + nt * 16, ldw);
                wmma::mma_sync(acc, fa, fb, acc);
            }
        }
        wmma::store_matrix_sync(scratch, acc, 16, wmma::mem_row_major);
        __syncwarp();
        const int row = lane >> 1, col = (lane & 1) * 8;
        float v[8];
#pragma unroll
        for (int j = 0; j < 8; ++j) v[j] = scratch[row * 16 + col + j];
        epi(row, nt * 16 + col, v);
        __syncwarp();
    }
}

// Pointers to the warp's first row in each activation buffer, with their row strides.
struct WarpRows {
    __half* x0;   // encoded input [16][32]
    __half* dh1;  // density hidden (after ReLU) [16][64]
    __half* cin;  // colour input [16][32]: density outputs, then SH
    __half* ch1;  // colour hidden 1 [16][64]
    __half* ch2;  // colour hidden 2 [16][64]
    int ld_x0, ld_dh1, ld_cin, ld_ch1, ld_ch2;
};

// Copies rows [row0, row0 + 16) of the encoded input into x0; rows at or past n become zeros.
__device__ __forceinline__ void load_input_rows(const __half* encoded, uint32_t row0, uint32_t n, __half* x0,
                                                int ld) {
    const int lane = threadIdx.x & 31;
#pragma unroll
    for (int j = 0; j < 2; ++j) {
        const int idx = lane + 32 * j;  // 64 pieces of 8 halves: 16 rows x 4
        const int r = idx >> 2, q = idx & 3;
        uint4 v = make_uint4(0, 0, 0, 0);
        if (row0 + uint32_t(r) < n)
            v = *reinterpret_cast<const uint4*>(encoded + size_t(row0 + r) * k_mlp_inputs + q * 8);
        *reinterpret_cast<uint4*>(x0 + r * ld + q * 8) = v;
    }
    __syncwarp();
}

// The forward pass of the warp's 16 rows. raw_sigma[r] gets the fp32 log-density output; dir(r) gives row
// r's view direction; color_epi(row, col, v) receives the colour layer's raw outputs (columns 0..2 valid).
template <bool density_only, typename DirFn, typename ColorEpi>
__device__ __forceinline__ void warp_forward(const __half* w, const WarpRows& b, float* raw_sigma, float* scratch,
                                             DirFn&& dir, ColorEpi&& color_epi) {
    warp_gemm<Pass::forward, 2>(b.x0, b.ld_x0, w + k_w_d0, 32, 4, scratch, [&](int r, int c, float v[8]) {
#pragma unroll
        for (int j = 0; j < 8; ++j) v[j] = fmaxf(v[j], 0.0f);
        store8(b.dh1 + r * b.ld_dh1 + c, v);
    });
    warp_gemm<Pass::forward, 4>(b.dh1, b.ld_dh1, w + k_w_d1, 64, 1, scratch, [&](int r, int c, float v[8]) {
        if (c == 0) raw_sigma[r] = v[0];
        if (!density_only) store8(b.cin + r * b.ld_cin + c, v);
    });
    if constexpr (density_only) return;
    const int lane = threadIdx.x & 31;
    if (lane < 16) {
        float sh[16];
        sh_encode_deg4(dir(lane), sh);
        store8(b.cin + lane * b.ld_cin + 16, sh);
        store8(b.cin + lane * b.ld_cin + 24, sh + 8);
    }
    __syncwarp();
    warp_gemm<Pass::forward, 2>(b.cin, b.ld_cin, w + k_w_c0, 32, 4, scratch, [&](int r, int c, float v[8]) {
#pragma unroll
        for (int j = 0; j < 8; ++j) v[j] = fmaxf(v[j], 0.0f);
        store8(b.ch1 + r * b.ld_ch1 + c, v);
    });
    warp_gemm<Pass::forward, 4>(b.ch1, b.ld_ch1, w + k_w_c1, 64, 4, scratch, [&](int r, int c, float v[8]) {
#pragma unroll
        for (int j = 0; j < 8; ++j) v[j] = fmaxf(v[j], 0.0f);
        store8(b.ch2 + r * b.ld_ch2 + c, v);
    });
    warp_gemm<Pass::forward, 4>(b.ch2, b.ld_ch2, w + k_w_c2, 64, 1, scratch, color_epi);
}

__device__ __forceinline__ void load_weights(__half* dst, const __half* src) {
    for (int i = threadIdx.x; i < k_mlp_half_weights / 8; i += blockDim.x)
        reinterpret_cast<uint4*>(dst)[i] = reinterpret_cast<const uint4*>(src)[i];
    __syncthreads();
}

__device__ __forceinline__ uint32_t sample_count(const uint32_t* count, uint32_t n_host, uint32_t capacity) {
    const uint32_t n = count ? *count : n_host;
    return n < capacity ? n : capacity;
}

// ---------------------------------------------------------------------------------------------------------
// Inference: two ping-pong buffers per warp (x0 -> dh1 -> cin -> ch1 -> ch2 alternate between them).

constexpr size_t k_infer_smem = size_t(k_mlp_half_weights) * 2 + 2 * size_t(k_rows) * k_ld64 * 2 +
                                size_t(k_warps) * 256 * 4 + size_t(k_rows) * 4;

template <bool density_only>
__global__ void __launch_bounds__(k_threads) mlp_inference_kernel(MlpInferenceArgs a) {
    extern __shared__ __align__(128) unsigned char smem[];
    __half* w = reinterpret_cast<__half*>(smem);
    __half* buf_a = w + k_mlp_half_weights;
    __half* buf_b = buf_a + k_rows * k_ld64;
    float* scratch_all = reinterpret_cast<float*>(buf_b + k_rows * k_ld64);
    float* raw_all = scratch_all + k_warps * 256;
    load_weights(w, a.weights);

    const uint32_t n = sample_count(a.count, a.n_host, a.capacity);
    const int warp = threadIdx.x >> 5, lane = threadIdx.x & 31;
    float* scratch = scratch_all + warp * 256;
    float* raw = raw_all + warp * 16;
    WarpRows b;
    b.x0 = b.cin = b.ch2 = buf_a + warp * 16 * k_ld64;
    b.dh1 = b.ch1 = buf_b + warp * 16 * k_ld64;
    b.ld_x0 = b.ld_dh1 = b.ld_cin = b.ld_ch1 = b.ld_ch2 = k_ld64;

    for (uint32_t tile = blockIdx.x; size_t(tile) * k_rows < n; tile += gridDim.x) {
        const uint32_t row0 = tile * k_rows + uint32_t(warp) * 16;
        if (row0 >= n) continue;  // warps are independent: no block barrier inside the loop
        load_input_rows(a.encoded, row0, n, b.x0, b.ld_x0);
        auto dir = [&](int r) {
            const uint32_t row = row0 + uint32_t(r);
            return row < n ? a.ray_dir[a.sample_ray[row]] : Vec3(0.0f, 0.0f, 1.0f);
        };
        warp_forward<density_only>(w, b, raw, scratch, dir, [&](int r, int c, float v[8]) {
            const uint32_t row = row0 + uint32_t(r);
            if (c == 0 && row < n) a.rgb[row] = Rgb(sigmoidf(v[0]), sigmoidf(v[1]), sigmoidf(v[2]));
        });
        if (lane < 16 && row0 + uint32_t(lane) < n) a.sigma[row0 + lane] = density_activation(raw[lane]);
        __syncwarp();
    }
}

// ---------------------------------------------------------------------------------------------------------
// Training: forward and backward of a tile, then the weight-gradient tiles over all 128 rows.

struct TrainSmem {
    static constexpr size_t w = 0;
    static constexpr size_t x0 = w + size_t(k_mlp_half_weights) * 2;
    static constexpr size_t dh1 = x0 + size_t(k_rows) * k_ld32 * 2;
    static constexpr size_t cin = dh1 + size_t(k_rows) * k_ld64 * 2;
    static constexpr size_t ch1 = cin + size_t(k_rows) * k_ld32 * 2;
    static constexpr size_t ch2 = ch1 + size_t(k_rows) * k_ld64 * 2;
    static constexpr size_t g_cout = ch2 + size_t(k_rows) * k_ld64 * 2;   // dL/d(colour output), [128][16]
    static constexpr size_t g_cz2 = g_cout + size_t(k_rows) * k_ld16 * 2; // dL/d(colour layer 1 pre-ReLU)
    static constexpr size_t g_cz1 = g_cz2 + size_t(k_rows) * k_ld64 * 2;  // dL/d(colour layer 0 pre-ReLU)
    static constexpr size_t g_dout = g_cz1 + size_t(k_rows) * k_ld64 * 2; // dL/d(density output), [128][16]
    static constexpr size_t g_dz1 = g_dout + size_t(k_rows) * k_ld16 * 2; // dL/d(density layer 0 pre-ReLU)
    static constexpr size_t scratch = g_dz1 + size_t(k_rows) * k_ld64 * 2;
    static constexpr size_t raw = scratch + size_t(k_warps) * 256 * 4;
    static constexpr size_t total = raw + size_t(k_rows) * 4;
};
static_assert(TrainSmem::total <= 227 * 1024, "fits one block per multiprocessor");
static_assert(TrainSmem::g_cout % 128 == 0 && TrainSmem::g_dz1 % 128 == 0 && TrainSmem::scratch % 128 == 0,
              "32-byte aligned buffers");

// One of the 40 weight-gradient tiles: dW[o][i] (16x16 at (ot, it)) = sum over rows of G[row][o] X[row][i].
struct GradTile {
    const __half* g;
    const __half* x;
    int ldg, ldx;
    int param_offset, inputs, valid_outputs;  // where the layer's weights start, its input width, rows kept
    int ot, it;
};

__device__ __forceinline__ GradTile grad_tile(int t, unsigned char* smem) {
    auto h = [&](size_t off) { return reinterpret_cast<const __half*>(smem + off); };
    GradTile g;
    if (t < 16) {  // colour layer 1: 64x64
        g = {h(TrainSmem::g_cz2), h(TrainSmem::ch1), k_ld64, k_ld64, k_w_c1, 64, 64, t >> 2, t & 3};
    } else if (t < 24) {  // colour layer 0: 64x32
        const int u = t - 16;
        g = {h(TrainSmem::g_cz1), h(TrainSmem::cin), k_ld64, k_ld32, k_w_c0, 32, 64, u >> 1, u & 1};
    } else if (t < 32) {  // density layer 0: 64x32
        const int u = t - 24;
        g = {h(TrainSmem::g_dz1), h(TrainSmem::x0), k_ld64, k_ld32, k_w_d0, 32, 64, u >> 1, u & 1};
    } else if (t < 36) {  // colour layer 2: 3x64 (padded to 16)
        g = {h(TrainSmem::g_cout), h(TrainSmem::ch2), k_ld16, k_ld64, k_w_c2, 64, 3, 0, t - 32};
    } else {  // density layer 1: 16x64
        g = {h(TrainSmem::g_dout), h(TrainSmem::dh1), k_ld16, k_ld64, k_w_d1, 64, 16, 0, t - 36};
    }
    return g;
}
constexpr int k_grad_tiles = 40;
constexpr int k_grad_tiles_per_warp = k_grad_tiles / k_warps;
static_assert(k_grad_tiles % k_warps == 0, "grad tiles spread evenly");

__global__ void __launch_bounds__(k_threads, 1) mlp_train_kernel(MlpTrainArgs a) {
    extern __shared__ __align__(128) unsigned char smem[];
    auto hp = [&](size_t off) { return reinterpret_cast<__half*>(smem + off); };
    const uint32_t n = sample_count(a.count, 0, a.capacity);
    if (size_t(blockIdx.x) * k_rows >= n) return;  // the whole block: nothing to add either
    __half* w = hp(TrainSmem::w);
    load_weights(w, a.weights);

    const float rays = float(*a.rays > 0 ? *a.rays : 1u);
    const float grad_scale = 1.0f / (a.loss_scale * rays);
    const int warp = threadIdx.x >> 5, lane = threadIdx.x & 31;
    float* scratch = reinterpret_cast<float*>(smem + TrainSmem::scratch) + warp * 256;
    float* raw = reinterpret_cast<float*>(smem + TrainSmem::raw) + warp * 16;
    const int r16 = warp * 16;
    WarpRows b;
    b.x0 = hp(TrainSmem::x0) + r16 * k_ld32;
    b.dh1 = hp(TrainSmem::dh1) + r16 * k_ld64;
    b.cin = hp(TrainSmem::cin) + r16 * k_ld32;
    b.ch1 = hp(TrainSmem::ch1) + r16 * k_ld64;
    b.ch2 = hp(TrainSmem::ch2) + r16 * k_ld64;
    b.ld_x0 = k_ld32, b.ld_dh1 = k_ld64, b.ld_cin = k_ld32, b.ld_ch1 = k_ld64, b.ld_ch2 = k_ld64;
    __half* g_cout = hp(TrainSmem::g_cout) + r16 * k_ld16;
    __half* g_cz2 = hp(TrainSmem::g_cz2) + r16 * k_ld64;
    __half* g_cz1 = hp(TrainSmem::g_cz1) + r16 * k_ld64;
    __half* g_dout = hp(TrainSmem::g_dout) + r16 * k_ld16;
    __half* g_dz1 = hp(TrainSmem::g_dz1) + r16 * k_ld64;
    const float ls = a.loss_scale;

    FragAcc dw[k_grad_tiles_per_warp];
#pragma unroll
    for (int j = 0; j < k_grad_tiles_per_warp; ++j) wmma::fill_fragment(dw[j], 0.0f);

    for (uint32_t tile = blockIdx.x; size_t(tile) * k_rows < n; tile += gridDim.x) {
        const uint32_t row0 = tile * k_rows + uint32_t(r16);
        // Rows past n are zeros in, zero gradients out, so whole-tile work stays correct (and the barriers
        // below are reached by every warp).
        load_input_rows(a.encoded, row0, n, b.x0, b.ld_x0);
        auto dir = [&](int r) {
            const uint32_t row = row0 + uint32_t(r);
            return row < n ? a.ray_dir[a.sample_ray[row]] : Vec3(0.0f, 0.0f, 1.0f);
        };
        // Forward; the colour epilogue turns dL/drgb into dL/d(raw colour) through the sigmoid.
        warp_forward<false>(w, b, raw, scratch, dir, [&](int r, int c, float v[8]) {
            const uint32_t row = row0 + uint32_t(r);
            float g[8] = {0, 0, 0, 0, 0, 0, 0, 0};
            if (c == 0 && row < n) {
                const Rgb d = a.d_rgb[row];
#pragma unroll
                for (int k = 0; k < 3; ++k) {
                    const float s = sigmoidf(v[k]);
                    g[k] = d[k] * s * (1.0f - s) * ls;
                }
            }
            store8_saturated(g_cout + r * k_ld16 + c, g);
        });
        // Backward through the colour MLP.
        warp_gemm<Pass::backward, 1>(g_cout, k_ld16, w + k_w_c2, 64, 4, scratch, [&](int r, int c, float v[8]) {
            float h[8];
            load8(b.ch2 + r * b.ld_ch2 + c, h);
#pragma unroll
            for (int j = 0; j < 8; ++j) v[j] = h[j] > 0.0f ? v[j] : 0.0f;
            store8_saturated(g_cz2 + r * k_ld64 + c, v);
        });
        warp_gemm<Pass::backward, 4>(g_cz2, k_ld64, w + k_w_c1, 64, 4, scratch, [&](int r, int c, float v[8]) {
            float h[8];
            load8(b.ch1 + r * b.ld_ch1 + c, h);
#pragma unroll
            for (int j = 0; j < 8; ++j) v[j] = h[j] > 0.0f ? v[j] : 0.0f;
            store8_saturated(g_cz1 + r * k_ld64 + c, v);
        });
        // Only the first 16 input columns of colour layer 0 (the density outputs) need a gradient; output 0
        // is also the log-density, whose gradient joins here.
        warp_gemm<Pass::backward, 4>(g_cz1, k_ld64, w + k_w_c0, 32, 1, scratch, [&](int r, int c, float v[8]) {
            const uint32_t row = row0 + uint32_t(r);
            if (c == 0 && row < n) v[0] += a.d_sigma[row] * density_activation_grad(raw[r]) * ls;
            store8_saturated(g_dout + r * k_ld16 + c, v);
        });
        // Backward through the density MLP, down to the encoding.
        warp_gemm<Pass::backward, 1>(g_dout, k_ld16, w + k_w_d1, 64, 4, scratch, [&](int r, int c, float v[8]) {
            float h[8];
            load8(b.dh1 + r * b.ld_dh1 + c, h);
#pragma unroll
            for (int j = 0; j < 8; ++j) v[j] = h[j] > 0.0f ? v[j] : 0.0f;
            store8_saturated(g_dz1 + r * k_ld64 + c, v);
        });
        warp_gemm<Pass::backward, 4>(g_dz1, k_ld64, w + k_w_d0, 32, 2, scratch, [&](int r, int c, float v[8]) {
            const uint32_t row = row0 + uint32_t(r);
            if (row >= n) return;
            float* dst = a.d_encoded + size_t(row) * k_mlp_inputs + c;
            reinterpret_cast<float4*>(dst)[0] =
                make_float4(v[0] * grad_scale, v[1] * grad_scale, v[2] * grad_scale, v[3] * grad_scale);
            reinterpret_cast<float4*>(dst)[1] =
                make_float4(v[4] * grad_scale, v[5] * grad_scale, v[6] * grad_scale, v[7] * grad_scale);
        });

        // Weight gradients over the whole tile.
        __syncthreads();
#pragma unroll
        for (int j = 0; j < k_grad_tiles_per_warp; ++j) {
            const GradTile gt = grad_tile(warp * k_grad_tiles_per_warp + j, smem);
#pragma unroll
            for (int kt = 0; kt < k_rows / 16; ++kt) {
                wmma::fragment<wmma::matrix_a, 16, 16, 16, __half, wmma::col_major> fa;  // G^T
                wmma::load_matrix_sync(fa, gt.g + kt * 16 * gt.ldg + gt.ot * 16, gt.ldg);
                wmma::fragment<wmma::matrix_b, 16, 16, 16, __half, wmma::row_major> fb;  // X
                wmma::load_matrix_sync(fb, gt.x + kt * 16 * gt.ldx + gt.it * 16, gt.ldx);
                wmma::mma_sync(dw[j], fa, fb, dw[j]);
            }
        }
        __syncthreads();
    }

    // Add this block's weight gradients to the global ones.
#pragma unroll
    for (int j = 0; j < k_grad_tiles_per_warp; ++j) {
        const GradTile gt = grad_tile(warp * k_grad_tiles_per_warp + j, smem);
        wmma::store_matrix_sync(scratch, dw[j], 16, wmma::mem_row_major);
        __syncwarp();
        for (int e = lane; e < 256; e += 32) {
            const int o = gt.ot * 16 + (e >> 4), i = gt.it * 16 + (e & 15);
            if (o < gt.valid_outputs) atomicAdd(a.d_weights + gt.param_offset + o * gt.inputs + i, scratch[e] * grad_scale);
        }
        __syncwarp();
    }
}

int multiprocessors() {
    static int count = [] {
        int dev = 0, sms = 0;
        cudaGetDevice(&dev);
        cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, dev);
        return sms > 0 ? sms : 1;
    }();
    return count;
}

int grid_for(uint32_t capacity, int blocks_per_sm) {
    const uint32_t tiles = (capacity + k_rows - 1) / k_rows;
    return int(std::max<uint32_t>(1, std::min<uint32_t>(tiles, uint32_t(multiprocessors() * blocks_per_sm))));
}

template <typename Kernel>
void allow_smem(Kernel kernel, size_t bytes) {
    gpu::cuda_check(cudaFuncSetAttribute(kernel, cudaFuncAttributeMaxDynamicSharedMemorySize, int(bytes)),
                    "cudaFuncSetAttribute (shared memory of the MLP kernels)");
}

}  // namespace

void mlp_inference(const MlpInferenceArgs& a, bool density_only, cudaStream_t stream) {
    if (a.capacity == 0) return;
    static const bool configured = [] {
        allow_smem(mlp_inference_kernel<true>, k_infer_smem);
        allow_smem(mlp_inference_kernel<false>, k_infer_smem);
        return true;
    }();
    (void)configured;
    const int blocks = grid_for(a.capacity, 3);
    if (density_only)
        mlp_inference_kernel<true><<<blocks, k_threads, k_infer_smem, stream>>>(a);
    else
        mlp_inference_kernel<false><<<blocks, k_threads, k_infer_smem, stream>>>(a);
    NPT_CUDA_CHECK_LAUNCH("mlp_inference_kernel");
}

void mlp_train(const MlpTrainArgs& a, cudaStream_t stream) {
    if (a.capacity == 0) return;
    static const bool configured = [] {
        allow_smem(mlp_train_kernel, TrainSmem::total);
        return true;
    }();
    (void)configured;
    mlp_train_kernel<<<grid_for(a.capacity, 1), k_threads, TrainSmem::total, stream>>>(a);
    NPT_CUDA_CHECK_LAUNCH("mlp_train_kernel");
}

}  // namespace npt::nerf::cuda
