// Kernels of the GPU view renderer (cuda_renderer.h): rays for every pixel, then rounds of "march a few more
// samples per live ray -> evaluate the field on them -> composite front to back (render_view.cpp's
// arithmetic) -> keep the rays that are neither opaque nor through". Finished pixels are written as they end.
#pragma once

#include <cuda_fp16.h>
#include <cuda_runtime.h>

#include <cstdint>

#include "core/vec.h"
#include "nerf/nerf_field.h"
#include "nerf/object_cut.h"
#include "nerf/pixel_ray.h"
#include "nerf/ray_march.h"

namespace npt::nerf::cuda {

struct RenderRay {
    Ray ray;  // model space, unit direction
    MarchCursor cursor;
    float tau = 0;  // optical depth so far
    Rgb color{0.0f, 0.0f, 0.0f};
};

struct RenderFrame {
    RenderRay* rays = nullptr;     // per pixel
    Vec3* dirs = nullptr;          // per pixel: the ray direction (the MLP reads it)
    float4* image = nullptr;       // per pixel: RGB over the background, alpha = 1 - T
    int width = 0, height = 0;
    Rgb background{1.0f, 1.0f, 1.0f};
    MarchParams march;
    OccupancyGridView grid;
    float min_transmittance = 1e-4f;
    Vec3 box_min{-1e30f, -1e30f, -1e30f}, box_max{1e30f, 1e30f, 1e30f};  // around the occupied cells
    ObjectCut object;  // active: the march passes over samples outside the object's box (object_only)
};

struct RenderSlots {              // the samples of a round, packed (each live ray reserves what it marched)
    Vec3* pos = nullptr;
    float* dt = nullptr;
    uint32_t* pixel = nullptr;    // the owner's pixel, or segment (index into the directions the MLP reads)
    uint32_t* first = nullptr;    // per live ray: its first sample this round
    uint8_t* used = nullptr;      // per live ray: samples this round (<= K)
    uint32_t* count = nullptr;    // device: samples this round (zero before the march)
    float4* scratch = nullptr;    // K per live ray: the march's own slots before packing
};

// Sets up every pixel's ray; pixels whose ray misses the model are written at once; the others go to
// `alive` (count in *alive_count, which must be zero before).
void render_init(const RenderFrame& f, const RayCamera& camera, uint32_t* alive, uint32_t* alive_count,
                 cudaStream_t s);
// Up to k samples for each of the n live rays, packed into the slots (at most n * k of them).
void render_march(const RenderFrame& f, const uint32_t* alive, uint32_t n, int k, RenderSlots slots,
                  cudaStream_t s);
// The fp32 reference evaluation of the field (NerfFieldView, the CPU's per-point code) on the round's samples
// (*slots.count of them; `capacity` bounds the launch).
void render_field_fp32(const NerfFieldView& field, const RenderSlots& slots, const Vec3* dirs, uint32_t capacity,
                       float* sigma, Rgb* rgb, cudaStream_t s);
// The fused evaluation (hash_encode, then the fp16 tensor-core MLPs: fused_mlp.h) on the round's samples, with
// colour: `params` the model's fp32 parameters, `mlp_half` its fp16 MLP weights, `encoded` capacity x 32 halves
// of scratch. `capacity` sizes the launches: pass field_rows(), not the whole buffer, or a round of a few samples
// launches blocks for millions that only find nothing to do (about 15 us a round in each kernel on the H200).
// The rows a round's field evaluation covers: its samples at most (`most`: live rays x samples each), in whole
// MLP tiles (128 rows: the MLP reads a tile's padding rows), within the `capacity` rows of the buffers.
inline uint32_t field_rows(uint64_t most, uint32_t capacity) {
    const uint64_t tiles = (most + 127) / 128 * 128;
    return tiles < capacity ? uint32_t(tiles) : capacity;
}
void render_field_fp16(const NerfLayout& layout, const float* params, const __half* mlp_half,
                       const RenderSlots& slots, const Vec3* dirs, uint32_t capacity, __half* encoded, float* sigma,
                       Rgb* rgb, cudaStream_t s);
// The same evaluation for the density alone (the colour MLP skipped; sigma as render_field_fp16 gives it).
void render_density_fp16(const NerfLayout& layout, const float* params, const __half* mlp_half,
                         const RenderSlots& slots, uint32_t capacity, __half* encoded, float* sigma, cudaStream_t s);
// Composites the round's samples; rays that go on are appended to next (count in *next_count, zero before).
void render_composite(const RenderFrame& f, const uint32_t* alive, uint32_t n, int k, RenderSlots slots,
                      const float* sigma, const Rgb* rgb, uint32_t* next, uint32_t* next_count, cudaStream_t s);

}  // namespace npt::nerf::cuda
