// The path tracer's OptiX pipeline: the module (the embedded OptiX-IR of device/optix_programs.cu), one program
// group per program, the linked pipeline with its stack sizes, and the shader binding table built from a small
// table of (program group, record) pairs: a ray-generation record, a miss and a hit-group record per ray type.
#pragma once

#include <optix_types.h>

#include <vector>

#include "core/cuda/device_buffer.h"

namespace npt::gpu {

class OptixPrograms {
  public:
    explicit OptixPrograms(OptixDeviceContext ctx);
    ~OptixPrograms();
    OptixPrograms(const OptixPrograms&) = delete;
    OptixPrograms& operator=(const OptixPrograms&) = delete;

    OptixPipeline pipeline() const { return m_pipeline; }
    const OptixShaderBindingTable& sbt() const { return m_sbt; }

  private:
    OptixModule m_module = nullptr;
    std::vector<OptixProgramGroup> m_groups;
    OptixPipeline m_pipeline = nullptr;
    DeviceBuffer<unsigned char> m_records;
    OptixShaderBindingTable m_sbt{};
};

}  // namespace npt::gpu
