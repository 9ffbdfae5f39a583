// The device buffers behind a round of the wavefront march (RenderSlots): the samples the live rays packed,
// what the field returned for them, and each ray's place in the list. Shared by the view renderer, the
// path tracer's NeRF pass and the relight stage's march, which size them differently.
#pragma once

#include <cuda_fp16.h>

#include <cstddef>
#include <cstdint>

#include "core/cuda/device_buffer.h"
#include "nerf/cuda/fused_mlp.h"
#include "nerf/cuda/render_kernels.h"

namespace npt::nerf::cuda {

struct SampleSlotBuffers {
    // Per sample slot.
    gpu::DeviceBuffer<Vec3> pos;
    gpu::DeviceBuffer<float> dt, sigma;
    gpu::DeviceBuffer<uint32_t> owner;  // the ray's pixel or segment
    gpu::DeviceBuffer<float4> scratch;  // the march's own slots before packing (K per live ray)
    gpu::DeviceBuffer<Rgb> rgb;
    gpu::DeviceBuffer<__half> encoded;  // the fp16 field's inputs, k_mlp_inputs per slot; empty for fp32
    // Per ray.
    gpu::DeviceBuffer<uint32_t> first;
    gpu::DeviceBuffer<uint8_t> used;

    size_t capacity() const { return pos.size(); }

    // Discards the contents. `what`/`lower` name the buffers and the setting to lower in an out-of-memory
    // error.
    void allocate(size_t samples, size_t rays, bool fp16_inputs, const char* what, const char* lower) {
        pos.allocate(samples, what, lower);
        dt.allocate(samples, what, lower);
        sigma.allocate(samples, what, lower);
        owner.allocate(samples, what, lower);
        scratch.allocate(samples, what, lower);
        rgb.allocate(samples, what, lower);
        if (fp16_inputs)
            encoded.allocate(samples * k_mlp_inputs, what, lower);
        else
            encoded.allocate(0);
        first.allocate(rays, what, lower);
        used.allocate(rays, what, lower);
    }

    // `count`: the device counter of the round's samples (zeroed before each march).
    RenderSlots view(uint32_t* count) {
        return {pos.data(), dt.data(), owner.data(), first.data(), used.data(), count, scratch.data()};
    }
};

}  // namespace npt::nerf::cuda
