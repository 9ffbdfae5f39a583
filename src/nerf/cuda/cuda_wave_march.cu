#include "nerf/cuda/cuda_wave_march.h"

#include <algorithm>
#include <string>

#include "core/cuda/device_buffer.h"
#include "core/cuda/warp_lists.cuh"
#include "core/error.h"
#include "nerf/cuda/cuda_device.h"
#include "nerf/cuda/march_slots.cuh"
#include "nerf/cuda/occupancy_bits.h"
#include "nerf/cuda/render_kernels.h"
#include "nerf/cuda/sample_slots.h"

namespace npt::nerf::cuda {

using gpu::cuda_check;
using gpu::DeviceBuffer;

namespace {

constexpr int k_block = 128;
// Sample slots of a round: a round evaluates at most this many samples (more where more rays are live, one
// slot each at least).
constexpr uint32_t k_min_slots = 1u << 22;
constexpr int k_first_round = 8;  // samples per live ray in the first round; doubles every round
constexpr int k_max_round = 64;

// A ray's march between rounds.
struct WaveState {
    MarchCursor cursor;
    float log_t = 0.0f;  // log transmittance (radiance and depth modes)
    float tau = 0.0f;    // optical depth (event mode)
};

unsigned blocks_for(uint32_t n) { return (n + k_block - 1) / k_block; }

__global__ void __launch_bounds__(k_block)
    init_kernel(WaveRay* rays, uint32_t n, MarchParams mp, OccupancyGridView grid, WaveState* state,
                Vec3* dirs, uint32_t* alive, uint32_t* alive_count) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    bool live = false;
    if (i < n) {
        WaveRay& r = rays[i];
        r.transmittance = 1.0f;
        r.radiance = Rgb(0.0f);
        r.depth = 0.0f;
        r.has_event = false;
        WaveState s;
        live = march_start(mp, grid, r.ray, r.jitter, &s.cursor);
        state[i] = s;
        dirs[i] = r.ray.d;
    }
    gpu::warp_append(live, i, alive, alive_count);
}

__global__ void __launch_bounds__(k_block)
    march_kernel(const WaveRay* rays, WaveState* state, const uint32_t* alive, uint32_t n, int k,
                 MarchParams mp, OccupancyGridView grid, RenderSlots slots) {
    const uint32_t a = blockIdx.x * blockDim.x + threadIdx.x;
    const bool live = a < n;
    const uint32_t i = live ? alive[a] : 0u;
    MarchCursor c;
    Ray ray{};
    if (live) {
        c = state[i].cursor;
        ray = rays[i].ray;
    }
    march_into_slots(live, a, i, mp, grid, ray, c, k, slots);
    if (live) state[i].cursor = c;
}

// The fp32 per-point field (the CPU's code), the colour only where it is wanted.
__global__ void __launch_bounds__(k_block)
    field_fp32_kernel(NerfFieldView field, RenderSlots slots, const Vec3* dirs, bool color, float* sigma,
                      Rgb* rgb) {
    const uint32_t m = *slots.count;
    for (uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < m; i += gridDim.x * blockDim.x) {
        if (color)
            field.query(slots.pos[i], dirs[slots.pixel[i]], &sigma[i], &rgb[i]);
        else
            sigma[i] = field.density(slots.pos[i]);
    }
}

// march_wavefront's step 3, sample by sample (wave_composite); rays that go on are appended to next.
__global__ void __launch_bounds__(k_block)
    composite_kernel(WaveRay* rays, WaveState* state, const uint32_t* alive, uint32_t n, WaveMode mode,
                     MarchParams mp, RenderSlots slots, const float* sigma, const Rgb* rgb, uint32_t* next,
                     uint32_t* next_count) {
    const uint32_t a = blockIdx.x * blockDim.x + threadIdx.x;
    bool go_on = false;
    uint32_t i = 0;
    if (a < n) {
        i = alive[a];
        WaveRay& r = rays[i];
        WaveState& s = state[i];
        float lt = s.log_t, tt = s.tau;
        bool stop = false;
        const uint32_t base = slots.first[a];
        const int used = slots.used[a];
        for (int k = 0; k < used && !stop; ++k) {
            const uint32_t q = base + uint32_t(k);
            stop = wave_composite(mode, r, lt, tt, slots.pos[q], sigma[q] * slots.dt[q],
                                  mode == WaveMode::radiance ? rgb[q] : Rgb(0.0f));
        }
        s.log_t = lt;
        s.tau = tt;
        go_on = !(stop || s.cursor.done(mp));
    }
    gpu::warp_append(go_on, i, next, next_count);
}

__global__ void __launch_bounds__(k_block)
    finish_kernel(WaveRay* rays, const WaveState* state, uint32_t n, WaveMode mode) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    rays[i].transmittance = wave_transmittance(mode, state[i].log_t, state[i].tau);
}

}  // namespace

struct CudaWaveMarcher::Impl {
    NerfLayout layout;
    MarchParams march;
    cudaStream_t stream = nullptr;
    DeviceBuffer<float> params;
    DeviceBuffer<uint32_t> occupied, coarse, counts;
    OccupancyGridView grid;
    // Per ray (grown to the largest call).
    DeviceBuffer<WaveRay> rays;
    DeviceBuffer<WaveState> state;
    DeviceBuffer<Vec3> dirs;
    DeviceBuffer<uint32_t> alive[2];
    // Per round.
    SampleSlotBuffers slots;
    uint32_t* host_count = nullptr;

    ~Impl() {
        if (host_count) cudaFreeHost(host_count);
        if (stream) cudaStreamDestroy(stream);
    }
    void reserve(size_t n);
    uint32_t read_count(int which);
};

void CudaWaveMarcher::Impl::reserve(size_t n) {
    constexpr const char* what = "the relight stage's rays";
    constexpr const char* lower = "--relight-points";
    if (n > rays.size()) {
        rays.allocate(n, what, lower);
        state.allocate(n, what, lower);
        dirs.allocate(n, what, lower);
        alive[0].allocate(n, what, lower);
        alive[1].allocate(n, what, lower);
    }
    // At least one sample slot per ray, so that every live ray takes part in every round.
    const size_t capacity = std::max<size_t>(k_min_slots, (n + 127) / 128 * 128);
    if (capacity > slots.capacity()) slots.allocate(capacity, capacity, false, what, lower);
}

uint32_t CudaWaveMarcher::Impl::read_count(int which) {
    cuda_check(
        cudaMemcpyAsync(host_count, counts.data() + which, sizeof(uint32_t), cudaMemcpyDeviceToHost, stream),
        "cudaMemcpyAsync");
    cuda_check(cudaStreamSynchronize(stream), "the relight stage's march");
    return *host_count;
}

CudaWaveMarcher::CudaWaveMarcher(const NerfModel& model) : m(std::make_unique<Impl>()) {
    Impl& I = *m;
    require_cuda_device();
    I.layout = model.layout();
    if (model.params.size() != I.layout.total) throw Error("the model's parameters do not match its layout");
    I.march = model.march_params();
    cuda_check(cudaStreamCreate(&I.stream), "cudaStreamCreate");
    I.params.upload(model.params, "the model parameters", "encoding.log2_table_size");
    const OccupancyBits bits = occupancy_bits(model.occupancy.view());
    I.occupied.upload(bits.occupied, "the occupancy grid", "occupancy.resolution");
    if (!bits.coarse.empty()) I.coarse.upload(bits.coarse, "the occupancy grid", "occupancy.resolution");
    I.grid = {nullptr, model.occupancy.cascades(), model.occupancy.resolution(), I.occupied.data(),
              I.coarse.size() ? I.coarse.data() : nullptr};
    I.counts.allocate(3);  // live rays (two lists), samples of the round
    cuda_check(cudaMallocHost(&I.host_count, sizeof(uint32_t)), "cudaMallocHost");
    cuda_check(cudaStreamSynchronize(I.stream), "uploading the model");
}

CudaWaveMarcher::~CudaWaveMarcher() = default;

void CudaWaveMarcher::march(std::vector<WaveRay>& host_rays, WaveMode mode) {
    Impl& I = *m;
    const size_t total = host_rays.size();
    if (total == 0) return;
    if (total >= (size_t(1) << 31))
        throw Error("relight: too many rays in one march (" + std::to_string(total) + ")");
    I.reserve(total);
    const uint32_t n = uint32_t(total);
    cuda_check(cudaMemcpyAsync(I.rays.data(), host_rays.data(), total * sizeof(WaveRay),
                               cudaMemcpyHostToDevice, I.stream),
               "cudaMemcpyAsync");
    const RenderSlots slots = I.slots.view(I.counts.data() + 2);
    cuda_check(cudaMemsetAsync(I.counts.data(), 0, 3 * sizeof(uint32_t), I.stream), "cudaMemsetAsync");
    init_kernel<<<blocks_for(n), k_block, 0, I.stream>>>(I.rays.data(), n, I.march, I.grid, I.state.data(),
                                                         I.dirs.data(), I.alive[0].data(), I.counts.data());
    NPT_CUDA_CHECK_LAUNCH("wave init_kernel");
    uint32_t live = I.read_count(0);
    int cur = 0;
    const bool color = mode == WaveMode::radiance;
    const uint32_t capacity = uint32_t(I.slots.capacity());  // >= one slot per ray (reserve)
    for (int k = k_first_round; live > 0; k = std::min(2 * k, k_max_round)) {
        const int kk = int(std::max<uint32_t>(1, std::min<uint32_t>(uint32_t(k), capacity / live)));
        const uint32_t most = live * uint32_t(kk);
        cuda_check(cudaMemsetAsync(slots.count, 0, sizeof(uint32_t), I.stream), "cudaMemsetAsync");
        march_kernel<<<blocks_for(live), k_block, 0, I.stream>>>(
            I.rays.data(), I.state.data(), I.alive[cur].data(), live, kk, I.march, I.grid, slots);
        NPT_CUDA_CHECK_LAUNCH("wave march_kernel");
        const NerfFieldView field(I.layout, I.params.data());
        field_fp32_kernel<<<std::min(blocks_for(most), 132u * 16u), k_block, 0, I.stream>>>(
            field, slots, I.dirs.data(), color, I.slots.sigma.data(), I.slots.rgb.data());
        NPT_CUDA_CHECK_LAUNCH("wave field_fp32_kernel");
        const int nxt = 1 - cur;
        cuda_check(cudaMemsetAsync(I.counts.data() + nxt, 0, sizeof(uint32_t), I.stream), "cudaMemsetAsync");
        composite_kernel<<<blocks_for(live), k_block, 0, I.stream>>>(
            I.rays.data(), I.state.data(), I.alive[cur].data(), live, mode, I.march, slots,
            I.slots.sigma.data(), I.slots.rgb.data(), I.alive[nxt].data(), I.counts.data() + nxt);
        NPT_CUDA_CHECK_LAUNCH("wave composite_kernel");
        live = I.read_count(nxt);
        cur = nxt;
    }
    finish_kernel<<<blocks_for(n), k_block, 0, I.stream>>>(I.rays.data(), I.state.data(), n, mode);
    NPT_CUDA_CHECK_LAUNCH("wave finish_kernel");
    cuda_check(cudaMemcpyAsync(host_rays.data(), I.rays.data(), total * sizeof(WaveRay),
                               cudaMemcpyDeviceToHost, I.stream),
               "cudaMemcpyAsync");
    cuda_check(cudaStreamSynchronize(I.stream), "the relight stage's march");
}

}  // namespace npt::nerf::cuda
