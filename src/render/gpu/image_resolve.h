// The path tracer's image from its per-slot sums on the device: the planes added in a fixed order and scaled
// by 1 / spp into interleaved RGB (or RGBA), so that a frame downloads 12 (16) bytes per pixel instead of 16 per
// slot; and the AOV layers from their planes (render/film.h).
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>

namespace npt::gpu {

// rgb[channels i + c] = scale * sum over z < slots of planes[z * pixels + i].c for c < 3; with channels 4 also
// the alpha, 1 - scale * the sum of .w (the transmittance of the camera rays that escaped, render/first_hit.h).
void resolve_image(const float4* planes, uint32_t slots, size_t pixels, float scale, int channels, float* rgb,
                   cudaStream_t s);

// The AOVs from first_hit's 2 * slots planes (optix_launch.h): albedo and normal 3 floats a pixel, depth 1;
// each may be null (not asked for).
void resolve_first_hits(const float4* first_hit, uint32_t slots, size_t pixels, float* albedo, float* normal,
                        float* depth, cudaStream_t s);

}  // namespace npt::gpu
