// The scene's acceleration structure: one geometry AS over every mesh's world-space triangles (as the CPU's
// Embree scene), one build input per mesh, so that a hit's SBT record (one per build input and ray type)
// names its mesh. A single level: without RT cores traversal runs on the SMs, and an instance level over
// overlapping meshes (a room's walls) costs a second traversal per ray. Compacted after the build.
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
    // The mesh index of each build input (meshes without triangles have none), in SBT order.
    const std::vector<uint32_t>& input_meshes() const { return m_input_meshes; }
    size_t bytes() const { return m_gas.bytes(); }

  private:
    std::vector<uint32_t> m_input_meshes;
    DeviceBuffer<unsigned char> m_gas;
    OptixTraversableHandle m_root = 0;
};

}  // namespace npt::gpu
