#include "core/cuda/device_buffer.h"
#include "core/cuda/warp_lists.cuh"
#include "nerf/cuda/march_slots.cuh"
#include "render/gpu/nerf_segment_kernels.h"

namespace npt::gpu {

namespace {

constexpr int k_block = 128;

unsigned blocks_for(uint32_t n) { return (n + k_block - 1) / k_block; }
unsigned warp_blocks_for(uint32_t warps) { return (warps + k_block / 32 - 1) / (k_block / 32); }

// The segment's result, where the path reads it.
__device__ __forceinline__ void write_result(const PathStore& paths, uint32_t item, Rgb radiance,
                                             float transmittance) {
    if (segment_kind(item) == 0)
        store_volume_result(paths, segment_path(item), radiance, transmittance);
    else
        store_shadow_transmittance(paths, segment_path(item), transmittance);
}

// A relit model's radiance segment is a free flight (volume_segment's SegmentRoute::Flight); its shadow segments
// are the emissive kind's attenuation only, which is march_relit_nerf's absorption to the same sample: the same
// sums of sigma dt, the same cut-off at T < 1e-4.
__device__ __forceinline__ bool is_flight(const NerfSegmentModel& m, uint32_t item) {
    return m.relit && segment_kind(item) == 0;
}

// After a round of a free flight: its event, or no event once the march has ended, is written into its path;
// true for a flight that goes on (its optical depth kept for the next round).
__device__ __forceinline__ bool flight_finish_or_keep(const NerfSegmentModel& m, const PathStore& paths,
                                                      uint32_t item, SegmentState& s, float log_t, bool event,
                                                      Vec3 p) {
    if (event) {
        const float t = flight_event_t(m.march, s.ray, s.cursor.t0, s.t_world, s.world_per_model, p);
        paths.events[segment_path(item)] = FlightEvent{p, t, m.volume};
        return false;
    }
    if (s.cursor.done(m.march)) {
        paths.events[segment_path(item)] = FlightEvent{};
        return false;
    }
    s.log_t = log_t;
    return true;
}

// FreeFlight::add over a round's samples, in order: each positive sigma dt (sigma times the density scale over
// the step) is added to the optical depth (-log_t), and the event is the first sample where it reaches the
// target. Returns that sample's index in the round, or -1.
__device__ __forceinline__ int flight_step(float& log_t, float target, const float* sigma, const float* dt,
                                           uint32_t base, int used, float density_scale) {
    for (int q = 0; q < used; ++q) {
        const float x = sigma[base + q] * density_scale * dt[base + q];
        if (!(x > 0.0f)) continue;  // also NaN, as FreeFlight::add
        log_t -= x;                 // exactly -(tau + x): negation does not round
        if (-log_t >= target) return q;
    }
    return -1;
}

// flight_step over the round's samples 32 at a time (the warp form): the optical depth at a sample is the
// state's plus an inclusive prefix sum over the lanes; the event is the first sample with a positive sigma dt
// where it reaches the target. The same sums as the sequential loop, added in another order. Every lane returns
// the event's index, or -1.
__device__ __forceinline__ int warp_flight_step(float& log_t, float target, const float* sigma, const float* dt,
                                                uint32_t base, int used, float density_scale) {
    constexpr unsigned all = 0xffffffffu;
    const int lane = int(threadIdx.x & 31);
    for (int q0 = 0; q0 < used; q0 += 32) {
        const int q = q0 + lane;
        float x = 0.0f;
        if (q < used) {
            x = sigma[base + q] * density_scale * dt[base + q];
            if (!(x > 0.0f)) x = 0.0f;
        }
        float through = x;
#pragma unroll
        for (int off = 1; off < 32; off <<= 1) {
            const float o = __shfl_up_sync(all, through, off);
            if (lane >= off) through += o;
        }
        const unsigned hits = __ballot_sync(all, x > 0.0f && -log_t + through >= target);
        if (hits != 0) {
            const int first = __ffs(hits) - 1;
            log_t -= __shfl_sync(all, through, first);
            return q0 + first;
        }
        log_t -= __shfl_sync(all, through, 31);
    }
    return -1;
}

// A segment's compositing where its last round left it.
__device__ __forceinline__ media::Accumulator resume(const SegmentState& s, uint32_t item) {
    media::Accumulator acc;
    acc.radiance = s.radiance;
    acc.log_t = s.log_t;
    acc.with_emission = segment_kind(item) == 0;
    return acc;
}

// After a round: a segment that turned opaque or reached its end is written into its path; true for one that
// goes on (its compositing kept for the next round).
__device__ __forceinline__ bool finish_or_keep(const NerfSegmentModel& m, const PathStore& paths,
                                               uint32_t item, SegmentState& s,
                                               const media::Accumulator& acc) {
    if (acc.done() || s.cursor.done(m.march)) {
        write_result(paths, item, acc.radiance, acc.done() ? 0.0f : expf(acc.log_t));
        return false;
    }
    s.radiance = acc.radiance;
    s.log_t = acc.log_t;
    return true;
}

__global__ void __launch_bounds__(k_block)
    gather_kernel(const uint32_t* queue, const uint32_t* active, uint32_t n, uint32_t* next,
                  uint32_t* next_count, SegmentLists lists) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    const bool in = i < n;
    const uint32_t id = in ? (active ? active[i] : i) : 0u;
    uint32_t slot[2] = {k_no_query, k_no_query};
    bool go_on = false;
    if (in) {
        const uint32_t word = queue[id];
        go_on = queue_going_on(word);
        slot[0] = queue_slot(word, 0);
        slot[1] = queue_slot(word, 1);
    }
    warp_append(go_on, id, next, next_count);
    const unsigned shadows = __ballot_sync(0xffffffffu, slot[1] != k_no_query);
    if ((threadIdx.x & 31) == 0 && shadows != 0) atomicAdd(lists.shadows, uint32_t(__popc(shadows)));
    // The same trip counts in every lane: warp_append needs them all.
    for (uint32_t l = 0; l < lists.lists; ++l)
        for (uint32_t kind = 0; kind < 2; ++kind)
            warp_append(slot[kind] == l, segment_item(id, int(kind)),
                        lists.items + size_t(l) * lists.capacity, lists.counts + l);
}

__global__ void __launch_bounds__(k_block)
    start_kernel(NerfSegmentModel m, PathStore paths, const uint32_t* list, uint32_t n, SegmentState* states,
                 Vec3* dirs, uint32_t* live, uint32_t* live_count) {
    const uint32_t j = blockIdx.x * blockDim.x + threadIdx.x;
    bool marching = false;
    if (j < n) {
        const NerfQuery q = paths.queries[2 * size_t(segment_path(list[j])) + size_t(segment_kind(list[j]))];
        nerf::MarchParams mp = m.march;
        mp.t_max = q.t_max;
        SegmentState s;
        s.ray = q.ray;
        s.target = q.target;
        s.t_world = q.t_world;
        s.world_per_model = q.world_per_model;
        // march_nerf's (and march_relit's) march (march_ray_visit with the lattice offset xi), clipped to the
        // occupied box, which leaves its samples as they are (ray_march.h).
        marching = nerf::march_start(mp, m.grid, q.ray, q.xi, &s.cursor) &&
                   nerf::march_clip(mp, q.ray, m.box_min, m.box_max, &s.cursor) && !s.cursor.done(mp);
        states[j] = s;
        dirs[j] = q.ray.d;
        if (!marching) {
            if (is_flight(m, list[j]))
                paths.events[segment_path(list[j])] = FlightEvent{};
            else
                write_result(paths, list[j], Rgb(0.0f), 1.0f);
        }
    }
    warp_append(marching, j, live, live_count);
}

__global__ void __launch_bounds__(k_block)
    march_kernel(NerfSegmentModel m, SegmentState* states, const uint32_t* live, uint32_t n, int k,
                 nerf::cuda::RenderSlots samples) {
    const uint32_t a = blockIdx.x * blockDim.x + threadIdx.x;
    const bool in = a < n;
    const uint32_t j = in ? live[a] : 0u;
    nerf::MarchCursor c;
    Ray ray{};
    if (in) {
        c = states[j].cursor;  // in registers while marching
        ray = states[j].ray;
    }
    nerf::cuda::march_into_slots(in, a, j, m.march, m.grid, ray, c, k, samples);
    if (in) states[j].cursor = c;
}

__global__ void __launch_bounds__(k_block)
    composite_kernel(NerfSegmentModel m, PathStore paths, const uint32_t* list, SegmentState* states,
                     const uint32_t* live, uint32_t n, nerf::cuda::RenderSlots samples, const float* sigma,
                     const Rgb* rgb, uint32_t* next, uint32_t* next_count) {
    const uint32_t a = blockIdx.x * blockDim.x + threadIdx.x;
    bool go_on = false;
    uint32_t j = 0;
    if (a < n) {
        j = live[a];
        const uint32_t item = list[j];
        const uint32_t base = samples.first[a];
        const int used = samples.used[a];
        if (is_flight(m, item)) {
            // media::march_relit's free flight, sample by sample (relit_free_flight.h).
            float log_t = states[j].log_t;
            const int e = flight_step(log_t, states[j].target, sigma, samples.dt, base, used, m.density_scale);
            go_on = flight_finish_or_keep(m, paths, item, states[j], log_t, e >= 0,
                                          e >= 0 ? samples.pos[base + uint32_t(e)] : Vec3(0.0f));
        } else {
            // media::march_nerf's compositing, sample by sample (volume_integrator.h).
            media::Accumulator acc = resume(states[j], item);
            for (int q = 0; q < used && !acc.done(); ++q)
                media::add_nerf_sample(acc, sigma[base + q], rgb[base + q], samples.dt[base + q],
                                       m.density_scale, m.emission_scale);
            go_on = finish_or_keep(m, paths, item, states[j], acc);
        }
    }
    warp_append(go_on, j, next, next_count);
}

// The warp forms of march and composite (one live segment per warp), for the rounds whose few long segments a
// thread each would march and composite as long dependent chains.
__global__ void __launch_bounds__(k_block)
    warp_march_kernel(NerfSegmentModel m, SegmentState* states, const uint32_t* live, uint32_t n, int k,
                      nerf::cuda::RenderSlots samples) {
    const uint32_t a = (blockIdx.x * blockDim.x + threadIdx.x) / 32;
    if (a >= n) return;  // a whole warp
    const uint32_t j = live[a];
    nerf::MarchCursor c = states[j].cursor;
    const Ray ray = states[j].ray;
    nerf::cuda::warp_march_into_slots(a, j, m.march, m.grid, ray, c, k, samples);
    if ((threadIdx.x & 31) == 0) states[j].cursor = c;
}

// add_nerf_sample over the round's samples 32 at a time: a sample is added while the transmittance before it
// is above the threshold (acc.done() false), that transmittance being the state's minus a prefix sum of the
// optical depths before it. The same sums as the sequential loop, added in another order.
__device__ __forceinline__ void warp_composite(media::Accumulator& acc, const float* sigma, const Rgb* rgb,
                                               const float* dt, uint32_t base, int used, float density_scale,
                                               float emission_scale) {
    constexpr unsigned all = 0xffffffffu;
    const int lane = int(threadIdx.x & 31);
    for (int q0 = 0; q0 < used && !acc.done(); q0 += 32) {
        const int q = q0 + lane;
        float tau = 0.0f;
        Rgb c(0.0f);
        if (q < used) {
            tau = sigma[base + q] * density_scale * dt[base + q];  // Accumulator::add's (sigma scale) len
            if (!(tau > 0.0f)) tau = 0.0f;                         // add() leaves such a sample out
            if (acc.with_emission) {
                const Rgb s = rgb[base + q];
                c = Rgb(srgb_to_linear(s.x), srgb_to_linear(s.y), srgb_to_linear(s.z)) * emission_scale;
            }
        }
        float through = tau;  // inclusive prefix sum of tau over the lanes
#pragma unroll
        for (int off = 1; off < 32; off <<= 1) {
            const float o = __shfl_up_sync(all, through, off);
            if (lane >= off) through += o;
        }
        const float log_before = acc.log_t - (through - tau);
        const bool added = q < used && !(log_before < media::k_log_min_transmittance);
        Rgb l = added && tau > 0.0f ? c * (expf(log_before) * -expm1f(-tau)) : Rgb(0.0f);
#pragma unroll
        for (int off = 16; off > 0; off >>= 1) {
            l.x += __shfl_xor_sync(all, l.x, off);
            l.y += __shfl_xor_sync(all, l.y, off);
            l.z += __shfl_xor_sync(all, l.z, off);
        }
        const unsigned took = __ballot_sync(all, added);
        if (took == 0) break;
        acc.radiance += l;
        acc.log_t -= __shfl_sync(all, through, 31 - __clz(took));  // through the last sample added
    }
}

__global__ void __launch_bounds__(k_block)
    warp_composite_kernel(NerfSegmentModel m, PathStore paths, const uint32_t* list, SegmentState* states,
                          const uint32_t* live, uint32_t n, nerf::cuda::RenderSlots samples,
                          const float* sigma, const Rgb* rgb, uint32_t* next, uint32_t* next_count) {
    const uint32_t a = (blockIdx.x * blockDim.x + threadIdx.x) / 32;
    if (a >= n) return;  // a whole warp
    const bool leader = (threadIdx.x & 31) == 0;
    const uint32_t j = live[a];
    if (is_flight(m, list[j])) {
        float log_t = states[j].log_t;
        const uint32_t base = samples.first[a];
        const int e = warp_flight_step(log_t, states[j].target, sigma, samples.dt, base, samples.used[a],
                                       m.density_scale);
        if (leader && flight_finish_or_keep(m, paths, list[j], states[j], log_t, e >= 0,
                                            e >= 0 ? samples.pos[base + uint32_t(e)] : Vec3(0.0f)))
            next[atomicAdd(next_count, 1u)] = j;
        return;
    }
    media::Accumulator acc = resume(states[j], list[j]);
    warp_composite(acc, sigma, rgb, samples.dt, samples.first[a], samples.used[a], m.density_scale,
                   m.emission_scale);
    if (leader && finish_or_keep(m, paths, list[j], states[j], acc)) next[atomicAdd(next_count, 1u)] = j;
}

}  // namespace

void segment_gather(const uint32_t* queue, const uint32_t* active, uint32_t n, uint32_t* next,
                    uint32_t* next_count, const SegmentLists& lists, cudaStream_t s) {
    if (n == 0) return;
    gather_kernel<<<blocks_for(n), k_block, 0, s>>>(queue, active, n, next, next_count, lists);
    NPT_CUDA_CHECK_LAUNCH("segment gather_kernel");
}

void segment_start(const NerfSegmentModel& m, const PathStore& paths, const uint32_t* list, uint32_t n,
                   SegmentState* states, Vec3* dirs, uint32_t* live, uint32_t* live_count, cudaStream_t s) {
    if (n == 0) return;
    start_kernel<<<blocks_for(n), k_block, 0, s>>>(m, paths, list, n, states, dirs, live, live_count);
    NPT_CUDA_CHECK_LAUNCH("segment start_kernel");
}

void segment_march(const NerfSegmentModel& m, SegmentState* states, const uint32_t* live, uint32_t n, int k,
                   bool by_warp, const nerf::cuda::RenderSlots& samples, cudaStream_t s) {
    if (n == 0) return;
    if (by_warp) {
        warp_march_kernel<<<warp_blocks_for(n), k_block, 0, s>>>(m, states, live, n, k, samples);
        NPT_CUDA_CHECK_LAUNCH("segment warp_march_kernel");
        return;
    }
    march_kernel<<<blocks_for(n), k_block, 0, s>>>(m, states, live, n, k, samples);
    NPT_CUDA_CHECK_LAUNCH("segment march_kernel");
}

void segment_composite(const NerfSegmentModel& m, const PathStore& paths, const uint32_t* list,
                       SegmentState* states, const uint32_t* live, uint32_t n, bool by_warp,
                       const nerf::cuda::RenderSlots& samples, const float* sigma, const Rgb* rgb,
                       uint32_t* next, uint32_t* next_count, cudaStream_t s) {
    if (n == 0) return;
    if (by_warp) {
        warp_composite_kernel<<<warp_blocks_for(n), k_block, 0, s>>>(m, paths, list, states, live, n, samples,
                                                                     sigma, rgb, next, next_count);
        NPT_CUDA_CHECK_LAUNCH("segment warp_composite_kernel");
        return;
    }
    composite_kernel<<<blocks_for(n), k_block, 0, s>>>(m, paths, list, states, live, n, samples, sigma, rgb,
                                                       next, next_count);
    NPT_CUDA_CHECK_LAUNCH("segment composite_kernel");
}

}  // namespace npt::gpu
