// The device memory of a wave of the wavefront path tracer (wavefront.h): the paths' states as planes of
// 16-byte words, their queries, and what a launch reads of the wave (WavefrontParams). Apart from
// wavefront.h, which the CPU tests include, because it needs CUDA's vector types.
#pragma once

#include <vector_types.h>  // uint4

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "render/gpu/wavefront.h"

namespace npt::gpu {

// The paths of a wave in device memory as planes of 16-byte words: word k of path i at words[k * stride + i].
// A warp's loads and stores of its paths' states are then coalesced (as an array of 240-byte structs, each
// 4-byte access of a warp touched 32 sectors, and the launches spent their time there), and the NeRF pass
// writes a result as one word. Beside them each path's two queries ([2i] the volume ray's, [2i + 1] the
// shadow ray's), read by the pass only for the segments queued, and its relit free flight's event (read by the
// next launch only where WavefrontPath::relit_flight says there was a flight).
constexpr uint32_t k_path_words = uint32_t((sizeof(WavefrontPath) + 15) / 16);
struct PathStore {
    uint4* words = nullptr;
    uint32_t stride = 0;  // the paths of the wave at most: each plane's length
    NerfQuery* queries = nullptr;
    FlightEvent* events = nullptr;  // one per path
};

NPT_HD NPT_INLINE WavefrontPath load_path(const PathStore& s, uint32_t i) {
    uint4 w[k_path_words];
    NPT_UNROLL
    for (uint32_t k = 0; k < k_path_words; ++k) w[k] = s.words[size_t(k) * s.stride + i];
    WavefrontPath p;
    std::memcpy(static_cast<void*>(&p), w, sizeof p);
    return p;
}
NPT_HD NPT_INLINE void store_path(const PathStore& s, uint32_t i, const WavefrontPath& p) {
    uint4 w[k_path_words] = {};
    std::memcpy(w, static_cast<const void*>(&p), sizeof p);
    NPT_UNROLL
    for (uint32_t k = 0; k < k_path_words; ++k) s.words[size_t(k) * s.stride + i] = w[k];
}

// The NeRF pass's results, written in place: the volume segment's (one word) or the shadow ray's
// transmittance.
constexpr size_t k_shadow_t_offset = offsetof(WavefrontPath, shadow_t);
static_assert(offsetof(WavefrontPath, vol) == 0 && sizeof(media::VolumeResult) == 16 &&
                  offsetof(media::VolumeResult, transmittance) == 12,
              "vol: word 0 of a path, as store_volume_result writes it");
static_assert(k_shadow_t_offset % 16 + sizeof(float) <= 16, "shadow_t: inside one word");
NPT_HD NPT_INLINE void store_volume_result(const PathStore& s, uint32_t i, Rgb radiance,
                                           float transmittance) {
    uint4 w;
    const float f[4] = {radiance.x, radiance.y, radiance.z, transmittance};
    std::memcpy(&w, f, sizeof w);
    s.words[i] = w;
}
NPT_HD NPT_INLINE void store_shadow_transmittance(const PathStore& s, uint32_t i, float transmittance) {
    uint4* w = s.words + (k_shadow_t_offset / 16) * size_t(s.stride) + i;
    reinterpret_cast<float*>(w)[(k_shadow_t_offset % 16) / 4] = transmittance;
}

// A wave of paths: every pixel, `slots` samples each (path i is sample sample_begin + i / pixels of pixel
// i % pixels).
struct WavefrontParams {
    PathStore paths;
    const uint32_t* active = nullptr;  // the paths of this launch; null in the first launch of a wave
    uint32_t* queue = nullptr;         // per path: its queue_word after the launch
    // Which volumes the NeRF pass takes: per scene volume, its slot in the pass, or k_no_query (grids, and
    // NeRFs the pass cannot evaluate; these are integrated inline).
    const uint32_t* nerf_slot = nullptr;
};

}  // namespace npt::gpu
