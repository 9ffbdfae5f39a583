// Kernels of the wavefront path tracer's NeRF pass (nerf_segments.h): gather the queued segments, start their
// marches, march a few samples per live segment, composite the evaluated samples. The field itself is
// evaluated between march and composite by the view renderer's kernels (hash_encode, mlp_inference).
#pragma once

#include <cuda_runtime.h>

#include <cstdint>

#include "core/platform.h"
#include "nerf/cuda/render_kernels.h"  // RenderSlots: the round's packed samples
#include "render/gpu/nerf_segments.h"

namespace npt::gpu {

// Where a segment's march stands and what it has gathered (media::Accumulator's radiance and log T; for a free
// flight log T is minus its optical depth so far, FreeFlight::tau). A free flight's target and world-t map are
// its query's (NerfQuery).
struct SegmentState {
    Ray ray;
    nerf::MarchCursor cursor;
    float log_t = 0.0f;
    Rgb radiance{0.0f};
    float target = INFINITY;
    float t_world = 0.0f;
    float world_per_model = 0.0f;
};

// A segment in a list: its path's index and which of the path's queries it is (kind 0: the volume ray, with
// emission; 1: the shadow ray, attenuation only) in the top bit.
NPT_HD NPT_INLINE uint32_t segment_item(uint32_t path, int kind) { return path | (uint32_t(kind) << 31); }
NPT_HD NPT_INLINE uint32_t segment_path(uint32_t item) { return item & 0x7fffffffu; }
NPT_HD NPT_INLINE int segment_kind(uint32_t item) { return int(item >> 31); }

// Lists of segments, one per model slot: list l is items[l * capacity ...], its length in counts[l] (zero
// before). A wave's paths number below 2^31.
struct SegmentLists {
    uint32_t* items = nullptr;
    uint32_t* counts = nullptr;
    uint32_t capacity = 0;
    uint32_t lists = 0;
    uint32_t* shadows = nullptr;  // device: shadow segments (kind 1) of all lists are added here (for stats)
};

// The paths of `active` (null: 0 .. n-1) that are not done go to `next`; their queued segments to the lists.
// From each path's queue_word (wavefront.h).
void segment_gather(const uint32_t* queue, const uint32_t* active, uint32_t n, uint32_t* next,
                    uint32_t* next_count, const SegmentLists& lists, cudaStream_t s);
// Starts the march of each of the n segments of `list`; a segment with nothing to march is written back at
// once (no emission, T = 1; a free flight without an event), the others go to `live`.
void segment_start(const NerfSegmentModel& m, const PathStore& paths, const uint32_t* list, uint32_t n,
                   SegmentState* states, Vec3* dirs, uint32_t* live, uint32_t* live_count, cudaStream_t s);
// Up to k samples for each of the n live segments. by_warp: a warp per segment (uniform steps only, see
// warp_march_into_slots), for the rounds of a few long segments; the samples are the same.
void segment_march(const NerfSegmentModel& m, SegmentState* states, const uint32_t* live, uint32_t n, int k,
                   bool by_warp, const nerf::cuda::RenderSlots& samples, cudaStream_t s);
// Composites the round's samples (by_warp: a warp per segment, as the march), or, for a relit model's radiance
// segments, looks for their free flight's event among them; finished segments are written into their paths, the
// others appended to next.
void segment_composite(const NerfSegmentModel& m, const PathStore& paths, const uint32_t* list,
                       SegmentState* states, const uint32_t* live, uint32_t n, bool by_warp,
                       const nerf::cuda::RenderSlots& samples, const float* sigma, const Rgb* rgb,
                       uint32_t* next, uint32_t* next_count, cudaStream_t s);

}  // namespace npt::gpu
