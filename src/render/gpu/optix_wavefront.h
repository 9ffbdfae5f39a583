// The host loop of the wavefront form (wavefront.h): a wave of paths (a part of the image, a few samples per
// pixel) is started by one launch of __raygen__wavefront, then "NeRF pass -> launch over the paths that go on"
// repeats until every path has written its sample. Each loop has its own stream, so that OptixRenderer can run
// two waves side by side from two host threads: one wave's launch fills the GPU while the other waits for a
// count (the pass synchronises once per round) or runs its nearly empty last bounces.
#pragma once

#include <cuda_runtime.h>
#include <optix_types.h>

#include <cstdint>

#include "core/cuda/device_buffer.h"
#include "render/gpu/nerf_segments.h"
#include "render/gpu/optix_launch.h"

namespace npt::gpu {

class OptixPrograms;

class WavefrontLoop {
  public:
    // host / device: the scene's volumes (SceneData's, DeviceScene's); max_paths: pixels x slots at most.
    WavefrontLoop(Span<const media::VolumeView> host, Span<const media::VolumeView> device, size_t max_paths);
    ~WavefrontLoop();
    WavefrontLoop(const WavefrontLoop&) = delete;
    WavefrontLoop& operator=(const WavefrontLoop&) = delete;
    // False: no NeRF in the scene that the NeRF pass takes; the per-thread form is as fast.
    bool useful() const { return m_pass.any(); }

    // Paths a wave of `slots` samples per pixel needs: wave `wave_index` of `wave_count` over `pixels`.
    static size_t wave_paths(size_t pixels, uint32_t slots, uint32_t wave_count);

    // Adds samples p.sample_begin .. + slots - 1 of the pixels of wave `wave_index` of `wave_count`
    // (wavefront.h, WavefrontParams; sample z into plane z of p.accum). Returns when they are in p.accum.
    // Thread-safe against other loops.
    void run_wave(LaunchParams p, uint32_t slots, uint32_t wave_index, uint32_t wave_count,
                  const OptixPrograms& programs);

  private:
    struct Stream {
        Stream();
        ~Stream();
        cudaStream_t s = nullptr;
    };
    Stream m_stream_owner;
    cudaStream_t m_stream;
    DeviceBuffer<LaunchParams> m_params{1};
    NerfSegmentPass m_pass;
    DeviceBuffer<WavefrontPath> m_paths;
    DeviceBuffer<uint32_t> m_active[2];
};

}  // namespace npt::gpu
