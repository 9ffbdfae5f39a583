// The path tracer's image from its per-slot sums on the device: the planes added in a fixed order and scaled
// by 1 / spp into interleaved RGB, so that a frame downloads 12 bytes per pixel instead of 16 per slot.
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>

namespace npt::gpu {

// rgb[3 i + c] = scale * sum over z < slots of planes[z * pixels + i].c
void resolve_image(const float4* planes, uint32_t slots, size_t pixels, float scale, float* rgb, cudaStream_t s);

}  // namespace npt::gpu
