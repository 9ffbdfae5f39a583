// The path tracer's OptiX pipeline: the modules (the embedded OptiX-IR of device/*.cu), one program
// group per program, the linked pipeline with its stack sizes, and the shader binding table built from a small
// table of (program group, record) pairs: a ray-generation record, a miss record per ray type, and a hit-group
// record per (mesh build input, ray type) that carries the mesh's index (optix_launch.h, HitRecordData).
#pragma once

#include <optix_types.h>

#include <cstdint>
#include <vector>

#include "core/cuda/device_buffer.h"

namespace npt::gpu {

class OptixPrograms {
  public:
    // input_meshes: the mesh index of each build input of the acceleration structure (optix_accel.h).
    OptixPrograms(OptixDeviceContext ctx, const std::vector<uint32_t>& input_meshes);
    ~OptixPrograms();
    OptixPrograms(const OptixPrograms&) = delete;
    OptixPrograms& operator=(const OptixPrograms&) = delete;

    OptixPipeline pipeline() const { return m_pipeline; }
    const OptixShaderBindingTable& sbt() const { return m_sbt; }
    // The same table with the wavefront form's ray-generation program (wavefront.h).
    const OptixShaderBindingTable& sbt_wavefront() const { return m_sbt_wavefront; }

  private:
    OptixModule m_module = nullptr;            // device/optix_programs.cu
    OptixModule m_wavefront_module = nullptr;  // device/optix_wavefront_programs.cu
    std::vector<OptixProgramGroup> m_groups;
    OptixPipeline m_pipeline = nullptr;
    DeviceBuffer<unsigned char> m_records;
    OptixShaderBindingTable m_sbt{};
    OptixShaderBindingTable m_sbt_wavefront{};
};

}  // namespace npt::gpu
