// The OptiX device context (the driver's OptiX 9 runtime, loaded at run time: no OptiX library is linked) and
// the error check every OptiX call goes through. Host code compiled with the OptiX headers only.
#pragma once

#include <optix_types.h>

namespace npt::gpu {

void optix_check(OptixResult r, const char* what);

class OptixContext {
  public:
    // Throws npt::Error with a one-line reason when the driver has no usable OptiX (missing, too old).
    OptixContext();
    ~OptixContext();
    OptixContext(const OptixContext&) = delete;
    OptixContext& operator=(const OptixContext&) = delete;
    OptixDeviceContext get() const { return m_ctx; }

  private:
    OptixDeviceContext m_ctx = nullptr;
};

}  // namespace npt::gpu
