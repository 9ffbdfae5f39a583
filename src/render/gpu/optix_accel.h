// The scene's acceleration structures: one geometry AS per mesh (world-space triangles, as the CPU's Embree
// scene) and an instance AS over them with identity transforms, so that an instance's id is its mesh's index
// (what the closest-hit program reports). Compacted after the build.
#pragma once

#include <cuda_runtime.h>
#include <optix_types.h>

#include <vector>

#include "core/cuda/device_buffer.h"
#include "render/gpu/device_scene.h"

namespace npt::gpu {

class OptixAccel {
  public:
    OptixAccel(OptixDeviceContext ctx, const DeviceScene& scene, cudaStream_t stream);
    OptixTraversableHandle handle() const { return m_root; }  // 0 for a scene without triangles
    size_t bytes() const;

  private:
    OptixTraversableHandle build(OptixDeviceContext ctx, const OptixBuildInput& input, bool compact,
                                 DeviceBuffer<unsigned char>& out, cudaStream_t stream);

    std::vector<DeviceBuffer<unsigned char>> m_gas;
    DeviceBuffer<OptixInstance> m_instances;
    DeviceBuffer<unsigned char> m_ias;
    OptixTraversableHandle m_root = 0;
};

}  // namespace npt::gpu
