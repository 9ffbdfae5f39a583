// The host loop of the wavefront form (wavefront.h): a wave of paths (every pixel, a few samples each) is
// started by one launch of __raygen__wavefront, then "NeRF pass -> launch over the paths that go on" repeats
// until every path has written its sample. Chosen by OptixRenderer for scenes with NeRF models.
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
    WavefrontLoop(Span<const media::VolumeView> host, Span<const media::VolumeView> device, size_t max_paths,
                  cudaStream_t stream);
    // False: no NeRF in the scene that the NeRF pass takes; the per-thread form is as fast.
    bool useful() const { return m_pass.any(); }

    // Adds samples p.sample_begin .. + slots - 1 of every pixel (sample z into plane z of p.accum); `params` is
    // the device copy of the launch parameters.
    void run_wave(LaunchParams p, uint32_t slots, const OptixPrograms& programs, LaunchParams* params);

  private:
    cudaStream_t m_stream;
    NerfSegmentPass m_pass;
    DeviceBuffer<uint4> m_path_words;  // PathStore's planes
    DeviceBuffer<NerfQuery> m_queries;  // two per path
    DeviceBuffer<FlightEvent> m_events;  // one per path
    uint32_t m_max_paths = 0;
    DeviceBuffer<uint32_t> m_active[2];
    DeviceBuffer<uint32_t> m_queue;  // per path: its queue_word (wavefront.h)
};

}  // namespace npt::gpu
