#include "render/gpu/optix_context.h"

#include <cuda_runtime.h>
#include <optix.h>
#include <optix_function_table_definition.h>  // defines the function table optix_stubs.h fills: once per binary
#include <optix_stubs.h>
#include <spdlog/spdlog.h>

#include <string>

#include "core/cuda/device_buffer.h"
#include "core/error.h"

namespace npt::gpu {

void optix_check(OptixResult r, const char* what) {
    if (r == OPTIX_SUCCESS) return;
    if (r == OPTIX_ERROR_DEVICE_OUT_OF_MEMORY || r == OPTIX_ERROR_HOST_OUT_OF_MEMORY)
        throw Error(std::string("GPU out of memory in ") + what + ": lower --res or simplify the scene");
    throw Error(std::string("OptiX: ") + what + ": " + optixGetErrorName(r) + " (" + optixGetErrorString(r) + ")");
}

namespace {
void log_message(unsigned int level, const char* tag, const char* message, void*) {
    if (level <= 2)
        spdlog::warn("OptiX [{}]: {}", tag, message);
    else
        spdlog::debug("OptiX [{}]: {}", tag, message);
}
}  // namespace

OptixContext::OptixContext() {
    cuda_check(cudaFree(nullptr), "initialising CUDA");  // makes the primary context current
    const OptixResult r = optixInit();
    if (r == OPTIX_ERROR_LIBRARY_NOT_FOUND)
        throw Error("--backend optix: the NVIDIA driver's OptiX library (libnvoptix.so.1) was not found (install "
                    "or update the NVIDIA driver)");
    if (r == OPTIX_ERROR_UNSUPPORTED_ABI_VERSION)
        throw Error("--backend optix: the NVIDIA driver is too old for OptiX 9 (update the driver to 570 or newer)");
    optix_check(r, "optixInit");
    OptixDeviceContextOptions options{};
    options.logCallbackFunction = log_message;
    options.logCallbackLevel = 3;
    optix_check(optixDeviceContextCreate(nullptr, &options, &m_ctx), "optixDeviceContextCreate");
}

OptixContext::~OptixContext() {
    if (m_ctx) optixDeviceContextDestroy(m_ctx);
}

}  // namespace npt::gpu
