// Fully fused NeRF MLPs on tensor cores (see fused_mlp.h), with mma.sync.m16n8k16 (fp16 operands, fp32
// accumulation) and the fragment layouts of the PTX ISA. A warp carries 16 samples through every layer; a
// layer's fp32 result fragments (16 x 8 tiles, lane (g, t) = (lane / 4, lane % 4) holding rows g and g + 8,
// columns 2t and 2t + 1) are exactly the next layer's fp16 A fragments once packed, so activations stay in
// registers from layer to layer. Weights sit in shared memory in the B fragments' layout: for y = x W^T the
// rows of W (row-major [out][in], padded by 8 halves so the 32 lanes' loads hit 32 banks); for the backward
// dx = dy W, the rows of W^T.
//
// Training (one block of 8 warps per 128 samples, a persistent grid): forward and backward per warp as above,
// with the activations X and the gradients G of each layer also written to shared memory; after one barrier
// the weight gradients dW = G^T X over all 128 rows (40 tiles of 16x16 with WMMA from those row-major
// buffers), accumulated in registers across the block's tiles and added to memory once at the end.
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

// Offsets of the layers in the global fp16 weight buffer (row-major [outputs][inputs], unpadded).
constexpr int k_g_d0 = 0;                  // density 0: [64][32]
constexpr int k_g_d1 = k_g_d0 + 64 * 32;   // density 1: [16][64]
constexpr int k_g_c0 = k_g_d1 + 16 * 64;   // colour 0:  [64][32]
constexpr int k_g_c1 = k_g_c0 + 64 * 32;   // colour 1:  [64][64]
constexpr int k_g_c2 = k_g_c1 + 64 * 64;   // colour 2:  [16][64], rows 3..15 zero
static_assert(k_g_c2 + 16 * 64 == k_mlp_half_weights, "weight buffer layout");

// Row strides (halves) of padded shared-memory matrices: width + 8 (conflict-free fragment loads).
constexpr int k_ld16 = 24, k_ld32 = 40, k_ld64 = 72;

// Forward weights in shared memory: W [out][in] with padded rows. The colour output layer needs 8 rows.
struct FwdW {
    static constexpr int d0 = 0;                 // [64][40]
    static constexpr int d1 = d0 + 64 * k_ld32;  // [16][72]
    static constexpr int c0 = d1 + 16 * k_ld64;  // [64][40]
    static constexpr int c1 = c0 + 64 * k_ld32;  // [64][72]
    static constexpr int c2 = c1 + 64 * k_ld64;  // [8][72]
    static constexpr int total = c2 + 8 * k_ld64;
};
// Backward weights: W^T [in][out] with padded rows; only what the backward reads.
struct BwdW {
    static constexpr int c2 = 0;                 // [64][24]: in 64, out 16 (3 real)
    static constexpr int c1 = c2 + 64 * k_ld16;  // [64][72]
    static constexpr int c0 = c1 + 64 * k_ld64;  // [16][72]: the 16 density-output inputs only
    static constexpr int d1 = c0 + 16 * k_ld64;  // [64][24]
    static constexpr int d0 = d1 + 64 * k_ld16;  // [32][72]
    static constexpr int total = d0 + 32 * k_ld64;
};

constexpr float k_half_max = 65504.0f;

__device__ __forceinline__ uint32_t pack_half2(float lo, float hi) {
    const __half2 h = __floats2half2_rn(lo, hi);
    return *reinterpret_cast<const uint32_t*>(&h);
}
__device__ __forceinline__ float2 unpack_half2(uint32_t u) {
    return __half22float2(*reinterpret_cast<const __half2*>(&u));
}
__device__ __forceinline__ float saturate_half(float v) { return fminf(fmaxf(v, -k_half_max), k_half_max); }

// d += a * b for one m16n8k16 tile.
__device__ __forceinline__ void mma16816(float (&d)[4], const uint32_t (&a)[4], uint32_t b0, uint32_t b1) {
    asm volatile(
        "mma.sync.aligned.m16n8k16.row.col.f32.f16.f16.f32 {%0,%1,%2,%3}, {%4,%5,%6,%7}, {%8,%9}, "
        "{%0,%1,%2,%3};\n"
        : "+f"(d[0]), "+f"(d[1]), "+f"(d[2]), "+f"(d[3])
        : "r"(a[0]), "r"(a[1]), "r"(a[2]), "r"(a[3]), "r"(b0), "r"(b1));
}

struct Lane {
    int g, t;  // group (row) and thread in group (column pair)
};
__device__ __forceinline__ Lane lane_id() {
    const int lane = threadIdx.x & 31;
    return {lane >> 2, lane & 3};
}

// out[n-tiles][4] = A (k-tiles of 16) x B. B[k][n] comes from shared memory rows: row n holds B[k][n] for
// consecutive k (the forward's W rows, the backward's W^T rows), ld halves apart.
template <int KT, int NT>
__device__ __forceinline__ void gemm(const uint32_t (&a)[KT][4], const __half* b, int ld, float (&out)[NT][4],
                                     Lane l) {
#pragma unroll
    for (int nt = 0; nt < NT; ++nt) {
        out[nt][0] = out[nt][1] = out[nt][2] = out[nt][3] = 0.0f;
        const __half* row = b + (nt * 8 + l.g) * ld + 2 * l.t;
#pragma unroll
        for (int kt = 0; kt < KT; ++kt) {
            const uint32_t b0 = *reinterpret_cast<const uint32_t*>(row + kt * 16);
            const uint32_t b1 = *reinterpret_cast<const uint32_t*>(row + kt * 16 + 8);
            mma16816(out[nt], a[kt], b0, b1);
        }
    }
}

// The result tiles of a layer (NT n-tiles of 8 columns) as the A fragments (NT/2 k-tiles) of the next.
template <int NT>
__device__ __forceinline__ void to_a(const float (&d)[NT][4], uint32_t (&a)[NT / 2][4]) {
#pragma unroll
    for (int kt = 0; kt < NT / 2; ++kt) {
        a[kt][0] = pack_half2(d[2 * kt][0], d[2 * kt][1]);          // row g,     columns 2t, 2t+1
        a[kt][1] = pack_half2(d[2 * kt][2], d[2 * kt][3]);          // row g + 8
        a[kt][2] = pack_half2(d[2 * kt + 1][0], d[2 * kt + 1][1]);  // row g,     columns 8 + 2t, 9 + 2t
        a[kt][3] = pack_half2(d[2 * kt + 1][2], d[2 * kt + 1][3]);  // row g + 8
    }
}

template <int NT>
__device__ __forceinline__ void relu(float (&d)[NT][4]) {
#pragma unroll
    for (int nt = 0; nt < NT; ++nt)
#pragma unroll
        for (int j = 0; j < 4; ++j) d[nt][j] = fmaxf(d[nt][j], 0.0f);
}

// Stores result tiles as halves into a row-major shared-memory matrix (the warp's first row at m).
template <int NT>
__device__ __forceinline__ void store_tiles(const float (&d)[NT][4], __half* m, int ld, Lane l, int col0 = 0) {
#pragma unroll
    for (int nt = 0; nt < NT; ++nt) {
        __half* p = m + l.g * ld + col0 + nt * 8 + 2 * l.t;
        *reinterpret_cast<uint32_t*>(p) = pack_half2(d[nt][0], d[nt][1]);
        *reinterpret_cast<uint32_t*>(p + 8 * ld) = pack_half2(d[nt][2], d[nt][3]);
    }
}

// Zeroes where the forward activation (row-major in shared memory) is not positive: the ReLU's gradient.
template <int NT>
__device__ __forceinline__ void relu_mask(float (&d)[NT][4], const __half* act, int ld, Lane l) {
#pragma unroll
    for (int nt = 0; nt < NT; ++nt) {
        const __half* p = act + l.g * ld + nt * 8 + 2 * l.t;
        const float2 h0 = unpack_half2(*reinterpret_cast<const uint32_t*>(p));
        const float2 h1 = unpack_half2(*reinterpret_cast<const uint32_t*>(p + 8 * ld));
        d[nt][0] = h0.x > 0.0f ? saturate_half(d[nt][0]) : 0.0f;
        d[nt][1] = h0.y > 0.0f ? saturate_half(d[nt][1]) : 0.0f;
        d[nt][2] = h1.x > 0.0f ? saturate_half(d[nt][2]) : 0.0f;
        d[nt][3] = h1.y > 0.0f ? saturate_half(d[nt][3]) : 0.0f;
    }
}

// A fragments of a 16 x (16 KT) block of a row-major fp16 matrix (global or shared), the warp's rows at m.
template <int KT>
__device__ __forceinline__ void load_a(uint32_t (&a)[KT][4], const __half* m, int ld, Lane l) {
#pragma unroll
    for (int kt = 0; kt < KT; ++kt) {
        const __half* p = m + l.g * ld + kt * 16 + 2 * l.t;
        a[kt][0] = *reinterpret_cast<const uint32_t*>(p);
        a[kt][1] = *reinterpret_cast<const uint32_t*>(p + 8 * ld);
        a[kt][2] = *reinterpret_cast<const uint32_t*>(p + 8);
        a[kt][3] = *reinterpret_cast<const uint32_t*>(p + 8 * ld + 8);
    }
}

// The SH coefficients of the colour input's second k-tile (columns 16 + 2t, 17 + 2t, 24 + 2t, 25 + 2t) for one
// row: selected with constant indices so that the coefficients stay in registers.
__device__ __forceinline__ void sh_pairs(Vec3 d, int t, uint32_t* lo, uint32_t* hi) {
    float sh[16];
    sh_encode_deg4(d, sh);
    const float a0 = t == 0 ? sh[0] : t == 1 ? sh[2] : t == 2 ? sh[4] : sh[6];
    const float a1 = t == 0 ? sh[1] : t == 1 ? sh[3] : t == 2 ? sh[5] : sh[7];
    const float b0 = t == 0 ? sh[8] : t == 1 ? sh[10] : t == 2 ? sh[12] : sh[14];
    const float b1 = t == 0 ? sh[9] : t == 1 ? sh[11] : t == 2 ? sh[13] : sh[15];
    *lo = pack_half2(a0, a1);
    *hi = pack_half2(b0, b1);
}

// Copies the global weights into shared memory: forward rows (padded) and, when `backward`, transposed rows.
// The forward weights alone (inference), 8 halves a load: the element-wise copy below took about 10 us in a
// launch of a few rows on the H200 (its loads wait for the stores before them, which may alias), the floor of
// every small round of the path tracer's NeRF pass. Rows and padded rows are whole multiples of 8 halves.
__device__ void load_forward_weights(__half* __restrict__ fwd, const __half* __restrict__ w) {
    using Chunk = uint4;  // 8 halves
    auto copy = [&](int dst, int src) {
        *reinterpret_cast<Chunk*>(fwd + dst) = *reinterpret_cast<const Chunk*>(w + src);
    };
    for (int i = threadIdx.x; i < 64 * 32 / 8; i += blockDim.x) {
        const int o = i / 4, k = (i % 4) * 8;
        copy(FwdW::d0 + o * k_ld32 + k, k_g_d0 + i * 8);
        copy(FwdW::c0 + o * k_ld32 + k, k_g_c0 + i * 8);
    }
    for (int i = threadIdx.x; i < 64 * 64 / 8; i += blockDim.x) {
        const int o = i / 8, k = (i % 8) * 8;
        copy(FwdW::c1 + o * k_ld64 + k, k_g_c1 + i * 8);
    }
    for (int i = threadIdx.x; i < 16 * 64 / 8; i += blockDim.x) {
        const int o = i / 8, k = (i % 8) * 8;
        copy(FwdW::d1 + o * k_ld64 + k, k_g_d1 + i * 8);
        if (o < 8) copy(FwdW::c2 + o * k_ld64 + k, k_g_c2 + i * 8);
    }
    __syncthreads();
}

__device__ void load_weights(__half* fwd, __half* bwd, const __half* w) {
    if (!bwd) {
        load_forward_weights(fwd, w);
        return;
    }
    for (int i = threadIdx.x; i < 64 * 32; i += blockDim.x) {
        const int o = i / 32, k = i % 32;
        fwd[FwdW::d0 + o * k_ld32 + k] = w[k_g_d0 + i];
        fwd[FwdW::c0 + o * k_ld32 + k] = w[k_g_c0 + i];
        if (bwd) {
            bwd[BwdW::d0 + k * k_ld64 + o] = w[k_g_d0 + i];
            if (k < 16) bwd[BwdW::c0 + k * k_ld64 + o] = w[k_g_c0 + i];
        }
    }
    for (int i = threadIdx.x; i < 64 * 64; i += blockDim.x) {
        const int o = i / 64, k = i % 64;
        fwd[FwdW::c1 + o * k_ld64 + k] = w[k_g_c1 + i];
        if (bwd) bwd[BwdW::c1 + k * k_ld64 + o] = w[k_g_c1 + i];
    }
    for (int i = threadIdx.x; i < 16 * 64; i += blockDim.x) {
        const int o = i / 64, k = i % 64;
        fwd[FwdW::d1 + o * k_ld64 + k] = w[k_g_d1 + i];
        if (o < 8) fwd[FwdW::c2 + o * k_ld64 + k] = w[k_g_c2 + i];
        if (bwd) {
            bwd[BwdW::d1 + k * k_ld16 + o] = w[k_g_d1 + i];
            bwd[BwdW::c2 + k * k_ld16 + o] = w[k_g_c2 + i];
        }
    }
    __syncthreads();
}

__device__ __forceinline__ uint32_t sample_count(const uint32_t* count, uint32_t n_host, uint32_t capacity) {
    const uint32_t n = count ? *count : n_host;
    return n < capacity ? n : capacity;
}

// Forward of the warp's 16 rows from their encoded input's A fragments. raw0[0..1]: the log-density of rows
// g and g + 8 (valid in lanes with t == 0); col[..]: the colour layer's raw outputs, columns 0..7 (3 real).
// When `keep` is set, every layer's input is also stored to the warp's rows of the shared buffers.
struct KeepRows {
    __half *dh1, *cin, *ch1, *ch2;
};
template <bool density_only, bool keep, typename DirFn>
__device__ __forceinline__ void forward(const uint32_t (&x0)[2][4], const __half* w, Lane l, DirFn&& dir,
                                        float (&raw0)[2], float (&col)[1][4], const KeepRows& k) {
    float h[8][4];
    uint32_t a[4][4];
    gemm<2, 8>(x0, w + FwdW::d0, k_ld32, h, l);
    relu(h);
    if constexpr (keep) store_tiles(h, k.dh1, k_ld64, l);
    to_a(h, a);
    float dout[2][4];
    gemm<4, 2>(a, w + FwdW::d1, k_ld64, dout, l);
    raw0[0] = dout[0][0];
    raw0[1] = dout[0][2];
    if constexpr (density_only) return;
    uint32_t cin[2][4], dens[1][4];
    to_a(dout, dens);
#pragma unroll
    for (int j = 0; j < 4; ++j) cin[0][j] = dens[0][j];
    sh_pairs(dir(l.g), l.t, &cin[1][0], &cin[1][2]);
    sh_pairs(dir(l.g + 8), l.t, &cin[1][1], &cin[1][3]);
    if constexpr (keep) {
        store_tiles(dout, k.cin, k_ld32, l);
        __half* p = k.cin + l.g * k_ld32 + 16 + 2 * l.t;
        *reinterpret_cast<uint32_t*>(p) = cin[1][0];
        *reinterpret_cast<uint32_t*>(p + 8 * k_ld32) = cin[1][1];
        *reinterpret_cast<uint32_t*>(p + 8) = cin[1][2];
        *reinterpret_cast<uint32_t*>(p + 8 * k_ld32 + 8) = cin[1][3];
    }
    gemm<2, 8>(cin, w + FwdW::c0, k_ld32, h, l);
    relu(h);
    if constexpr (keep) store_tiles(h, k.ch1, k_ld64, l);
    to_a(h, a);
    gemm<4, 8>(a, w + FwdW::c1, k_ld64, h, l);
    relu(h);
    if constexpr (keep) store_tiles(h, k.ch2, k_ld64, l);
    to_a(h, a);
    gemm<4, 1>(a, w + FwdW::c2, k_ld64, col, l);
}

// ---------------------------------------------------------------------------------------------------------
// Inference.

constexpr size_t k_infer_smem = size_t(FwdW::total) * 2;

template <bool density_only>
__global__ void __launch_bounds__(k_threads) mlp_inference_kernel(MlpInferenceArgs a) {
    extern __shared__ __align__(128) unsigned char smem[];
    __half* w = reinterpret_cast<__half*>(smem);
    load_weights(w, nullptr, a.weights);
    const uint32_t n = sample_count(a.count, a.n_host, a.capacity);
    const Lane l = lane_id();
    const uint32_t warps = gridDim.x * k_warps;
    for (uint32_t slice = blockIdx.x * k_warps + (threadIdx.x >> 5); size_t(slice) * 16 < n; slice += warps) {
        const uint32_t row0 = slice * 16;
        // Rows past n read the buffer's padding (capacity is whole tiles) and are not written back.
        uint32_t x0[2][4];
        load_a(x0, a.encoded + size_t(row0) * k_mlp_inputs, k_mlp_inputs, l);
        auto dir = [&](int r) {
            const uint32_t row = row0 + uint32_t(r);
            return row < n ? a.ray_dir[a.sample_ray[row]] : Vec3(0.0f, 0.0f, 1.0f);
        };
        float raw0[2], col[1][4];
        forward<density_only, false>(x0, w, l, dir, raw0, col, KeepRows{});
        const uint32_t r0 = row0 + uint32_t(l.g), r1 = r0 + 8;
        if (l.t == 0) {
            if (r0 < n) a.sigma[r0] = density_activation(raw0[0]);
            if (r1 < n) a.sigma[r1] = density_activation(raw0[1]);
        }
        if constexpr (!density_only) {
            // Lane t = 0 holds colours 0 and 1, lane t = 1 colour 2 (and the zero padding column 3).
            if (l.t < 2) {
                float* c0 = reinterpret_cast<float*>(a.rgb + (r0 < n ? r0 : 0));
                float* c1 = reinterpret_cast<float*>(a.rgb + (r1 < n ? r1 : 0));
                if (l.t == 0) {
                    if (r0 < n) c0[0] = sigmoidf(col[0][0]), c0[1] = sigmoidf(col[0][1]);
                    if (r1 < n) c1[0] = sigmoidf(col[0][2]), c1[1] = sigmoidf(col[0][3]);
                } else {
                    if (r0 < n) c0[2] = sigmoidf(col[0][0]);
                    if (r1 < n) c1[2] = sigmoidf(col[0][2]);
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------------------
// Training.

struct TrainSmem {
    static constexpr size_t wf = 0;
    static constexpr size_t wb = wf + size_t(FwdW::total) * 2;
    static constexpr size_t x0 = (wb + size_t(BwdW::total) * 2 + 127) / 128 * 128;
    static constexpr size_t dh1 = x0 + size_t(k_rows) * k_ld32 * 2;
    static constexpr size_t cin = dh1 + size_t(k_rows) * k_ld64 * 2;
    static constexpr size_t ch1 = cin + size_t(k_rows) * k_ld32 * 2;
    static constexpr size_t ch2 = ch1 + size_t(k_rows) * k_ld64 * 2;
    static constexpr size_t g_cout = ch2 + size_t(k_rows) * k_ld64 * 2;   // dL/d(colour output), 16 columns
    static constexpr size_t g_cz2 = g_cout + size_t(k_rows) * k_ld16 * 2; // dL/d(colour layer 1, pre-ReLU)
    static constexpr size_t g_cz1 = g_cz2 + size_t(k_rows) * k_ld64 * 2;  // dL/d(colour layer 0, pre-ReLU)
    static constexpr size_t g_dout = g_cz1 + size_t(k_rows) * k_ld64 * 2; // dL/d(density output)
    static constexpr size_t g_dz1 = g_dout + size_t(k_rows) * k_ld16 * 2; // dL/d(density layer 0, pre-ReLU)
    static constexpr size_t scratch = g_dz1 + size_t(k_rows) * k_ld64 * 2;
    static constexpr size_t total = scratch + size_t(k_warps) * 256 * 4;
};
static_assert(TrainSmem::total <= 227 * 1024, "fits one block per multiprocessor");
static_assert(TrainSmem::x0 % 128 == 0 && TrainSmem::g_cout % 128 == 0 && TrainSmem::scratch % 128 == 0,
              "aligned buffers");

// One of the 40 weight-gradient tiles: dW[o][i] (16x16 at (ot, it)) = sum over rows of G[row][o] X[row][i].
struct GradTile {
    const __half* g;
    const __half* x;
    int ldg, ldx;
    int param_offset, inputs, valid_outputs;  // where the layer's weights start, its input width, rows kept
    int ot, it;
};

__device__ __forceinline__ GradTile grad_tile(int t, const unsigned char* smem) {
    auto h = [&](size_t off) { return reinterpret_cast<const __half*>(smem + off); };
    GradTile g;
    if (t < 16) {  // colour layer 1: 64x64
        g = {h(TrainSmem::g_cz2), h(TrainSmem::ch1), k_ld64, k_ld64, k_g_c1, 64, 64, t >> 2, t & 3};
    } else if (t < 24) {  // colour layer 0: 64x32
        const int u = t - 16;
        g = {h(TrainSmem::g_cz1), h(TrainSmem::cin), k_ld64, k_ld32, k_g_c0, 32, 64, u >> 1, u & 1};
    } else if (t < 32) {  // density layer 0: 64x32
        const int u = t - 24;
        g = {h(TrainSmem::g_dz1), h(TrainSmem::x0), k_ld64, k_ld32, k_g_d0, 32, 64, u >> 1, u & 1};
    } else if (t < 36) {  // colour layer 2: 3x64 (padded to 16)
        g = {h(TrainSmem::g_cout), h(TrainSmem::ch2), k_ld16, k_ld64, k_g_c2, 64, 3, 0, t - 32};
    } else {  // density layer 1: 16x64
        g = {h(TrainSmem::g_dout), h(TrainSmem::dh1), k_ld16, k_ld64, k_g_d1, 64, 16, 0, t - 36};
    }
    return g;
}
constexpr int k_grad_tiles = 40;
constexpr int k_grad_tiles_per_warp = k_grad_tiles / k_warps;
static_assert(k_grad_tiles % k_warps == 0, "grad tiles spread evenly");

__global__ void __launch_bounds__(k_threads, 1) mlp_train_kernel(MlpTrainArgs a) {
    extern __shared__ __align__(128) unsigned char smem[];
    const uint32_t n = sample_count(a.count, 0, a.capacity);
    if (size_t(blockIdx.x) * k_rows >= n) return;  // the whole block: nothing to add either
    auto hp = [&](size_t off) { return reinterpret_cast<__half*>(smem + off); };
    const __half* wf = hp(TrainSmem::wf);
    const __half* wb = hp(TrainSmem::wb);
    load_weights(hp(TrainSmem::wf), hp(TrainSmem::wb), a.weights);

    const float rays = float(*a.rays > 0 ? *a.rays : 1u);
    const float grad_scale = 1.0f / (a.loss_scale * rays);
    const float ls = a.loss_scale;
    const int warp = threadIdx.x >> 5;
    const Lane l = lane_id();
    const int r16 = warp * 16;
    float* scratch = reinterpret_cast<float*>(smem + TrainSmem::scratch) + warp * 256;
    __half* x0s = hp(TrainSmem::x0) + r16 * k_ld32;
    const KeepRows keep{hp(TrainSmem::dh1) + r16 * k_ld64, hp(TrainSmem::cin) + r16 * k_ld32,
                        hp(TrainSmem::ch1) + r16 * k_ld64, hp(TrainSmem::ch2) + r16 * k_ld64};
    __half* g_cout = hp(TrainSmem::g_cout) + r16 * k_ld16;
    __half* g_cz2 = hp(TrainSmem::g_cz2) + r16 * k_ld64;
    __half* g_cz1 = hp(TrainSmem::g_cz1) + r16 * k_ld64;
    __half* g_dout = hp(TrainSmem::g_dout) + r16 * k_ld16;
    __half* g_dz1 = hp(TrainSmem::g_dz1) + r16 * k_ld64;

    wmma::fragment<wmma::accumulator, 16, 16, 16, float> dw[k_grad_tiles_per_warp];
#pragma unroll
    for (int j = 0; j < k_grad_tiles_per_warp; ++j) wmma::fill_fragment(dw[j], 0.0f);

    for (uint32_t tile = blockIdx.x; size_t(tile) * k_rows < n; tile += gridDim.x) {
        const uint32_t row0 = tile * k_rows + uint32_t(r16);
        const uint32_t r0 = row0 + uint32_t(l.g), r1 = r0 + 8;
        const bool v0 = r0 < n, v1 = r1 < n;
        // The input rows into shared memory (zeros past n: zero gradients out, and every warp reaches the
        // barriers below), then its A fragments.
        {
            const int lane = threadIdx.x & 31;
#pragma unroll
            for (int j = 0; j < 2; ++j) {
                const int idx = lane + 32 * j, r = idx >> 2, q = idx & 3;
                uint4 v = make_uint4(0, 0, 0, 0);
                if (row0 + uint32_t(r) < n)
                    v = *reinterpret_cast<const uint4*>(a.encoded + size_t(row0 + r) * k_mlp_inputs + q * 8);
                *reinterpret_cast<uint4*>(x0s + r * k_ld32 + q * 8) = v;
            }
            __syncwarp();
        }
        uint32_t x0[2][4];
        load_a(x0, x0s, k_ld32, l);
        auto dir = [&](int r) {
            const uint32_t row = row0 + uint32_t(r);
            return row < n ? a.ray_dir[a.sample_ray[row]] : Vec3(0.0f, 0.0f, 1.0f);
        };
        float raw0[2], col[1][4];
        forward<false, true>(x0, wf, l, dir, raw0, col, keep);

        // dL/d(raw colour): lane t = 0 has colours 0, 1 of rows g, g + 8; lane t = 1 colour 2 (and padding).
        float gc[1][4] = {{0.0f, 0.0f, 0.0f, 0.0f}};
        if (l.t < 2) {
            const Rgb d0 = v0 ? a.d_rgb[r0] : Rgb(0.0f), d1 = v1 ? a.d_rgb[r1] : Rgb(0.0f);
            auto grad = [&](float raw, float d) {
                const float s = sigmoidf(raw);
                return saturate_half(d * s * (1.0f - s) * ls);
            };
            if (l.t == 0) {
                gc[0][0] = grad(col[0][0], d0.x), gc[0][1] = grad(col[0][1], d0.y);
                gc[0][2] = grad(col[0][2], d1.x), gc[0][3] = grad(col[0][3], d1.y);
            } else {
                gc[0][0] = grad(col[0][0], d0.z);
                gc[0][2] = grad(col[0][2], d1.z);
            }
        }
        store_tiles(gc, g_cout, k_ld16, l);
        {  // columns 8..15 of the padded colour gradient are zero
            __half* p = g_cout + l.g * k_ld16 + 8 + 2 * l.t;
            *reinterpret_cast<uint32_t*>(p) = 0u;
            *reinterpret_cast<uint32_t*>(p + 8 * k_ld16) = 0u;
        }
        uint32_t ga16[1][4] = {{pack_half2(gc[0][0], gc[0][1]), pack_half2(gc[0][2], gc[0][3]), 0u, 0u}};

        // Backward through the colour MLP.
        float d[8][4];
        uint32_t ga[4][4];
        gemm<1, 8>(ga16, wb + BwdW::c2, k_ld16, d, l);
        relu_mask(d, keep.ch2, k_ld64, l);
        store_tiles(d, g_cz2, k_ld64, l);
        to_a(d, ga);
        gemm<4, 8>(ga, wb + BwdW::c1, k_ld64, d, l);
        relu_mask(d, keep.ch1, k_ld64, l);
        store_tiles(d, g_cz1, k_ld64, l);
        to_a(d, ga);
        // Only the 16 density-output inputs of colour layer 0 need a gradient; output 0 is also the
        // log-density, whose gradient joins here.
        float dd[2][4];
        gemm<4, 2>(ga, wb + BwdW::c0, k_ld64, dd, l);
        if (l.t == 0) {
            if (v0) dd[0][0] += a.d_sigma[r0] * density_activation_grad(raw0[0]) * ls;
            if (v1) dd[0][2] += a.d_sigma[r1] * density_activation_grad(raw0[1]) * ls;
        }
#pragma unroll
        for (int nt = 0; nt < 2; ++nt)
#pragma unroll
            for (int j = 0; j < 4; ++j) dd[nt][j] = saturate_half(dd[nt][j]);
        store_tiles(dd, g_dout, k_ld16, l);
        uint32_t gd16[1][4];
        to_a(dd, gd16);
        // Backward through the density MLP, down to the encoding.
        gemm<1, 8>(gd16, wb + BwdW::d1, k_ld16, d, l);
        relu_mask(d, keep.dh1, k_ld64, l);
        store_tiles(d, g_dz1, k_ld64, l);
        to_a(d, ga);
        float de[4][4];
        gemm<4, 4>(ga, wb + BwdW::d0, k_ld64, de, l);
#pragma unroll
        for (int nt = 0; nt < 4; ++nt) {
            const int c = nt * 8 + 2 * l.t;
            if (v0)
                *reinterpret_cast<float2*>(a.d_encoded + size_t(r0) * k_mlp_inputs + c) =
                    make_float2(de[nt][0] * grad_scale, de[nt][1] * grad_scale);
            if (v1)
                *reinterpret_cast<float2*>(a.d_encoded + size_t(r1) * k_mlp_inputs + c) =
                    make_float2(de[nt][2] * grad_scale, de[nt][3] * grad_scale);
        }

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
    const int lane = threadIdx.x & 31;
#pragma unroll
    for (int j = 0; j < k_grad_tiles_per_warp; ++j) {
        const GradTile gt = grad_tile(warp * k_grad_tiles_per_warp + j, smem);
        wmma::store_matrix_sync(scratch, dw[j], 16, wmma::mem_row_major);
        __syncwarp();
        for (int e = lane; e < 256; e += 32) {
            const int o = gt.ot * 16 + (e >> 4), i = gt.it * 16 + (e & 15);
            if (o < gt.valid_outputs)
                atomicAdd(a.d_weights + gt.param_offset + o * gt.inputs + i, scratch[e] * grad_scale);
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
    const int blocks = grid_for(a.capacity, 4);
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
