#include "nerf/cuda/cuda_device.h"

#include <cuda_runtime.h>

#include <fmt/format.h>

#include "core/error.h"

namespace npt::nerf::cuda {

namespace {

bool probe(std::string* why, cudaDeviceProp* prop_out) {
    int count = 0;
    const cudaError_t e = cudaGetDeviceCount(&count);
    if (e == cudaErrorNoDevice || (e == cudaSuccess && count == 0)) {
        if (why) *why = "no CUDA GPU was found";
        return false;
    }
    if (e == cudaErrorInsufficientDriver) {
        int driver = 0;
        cudaDriverGetVersion(&driver);  // 0 when no driver is installed at all
        if (why)
            *why = driver == 0 ? "no NVIDIA driver is installed (no CUDA GPU here)"
                               : "the NVIDIA driver is older than this build's CUDA runtime (update the driver)";
        return false;
    }
    if (e != cudaSuccess) {
        if (why) *why = std::string("the CUDA driver cannot be used: ") + cudaGetErrorString(e);
        return false;
    }
    cudaDeviceProp prop{};
    if (cudaGetDeviceProperties(&prop, 0) != cudaSuccess) {
        if (why) *why = "cannot read the GPU's properties";
        return false;
    }
    if (prop.major < 7) {
        if (why)
            *why = std::string(prop.name) + " (compute capability " + std::to_string(prop.major) + "." +
                   std::to_string(prop.minor) + ") has no tensor cores; 7.0 or newer is needed";
        return false;
    }
    if (prop_out) *prop_out = prop;
    return true;
}

}  // namespace

bool cuda_device_usable(std::string* why) { return probe(why, nullptr); }

std::string require_cuda_device() {
    std::string why;
    cudaDeviceProp prop{};
    if (!probe(&why, &prop)) throw Error("--backend cuda: " + why);
    if (cudaSetDevice(0) != cudaSuccess) throw Error("--backend cuda: cannot select GPU 0");
    int driver = 0;
    cudaDriverGetVersion(&driver);
    return fmt::format("{} (sm_{}{}, {} SMs, {:.1f} GiB, driver CUDA {}.{})", prop.name, prop.major, prop.minor,
                       prop.multiProcessorCount, double(prop.totalGlobalMem) / (1024.0 * 1024.0 * 1024.0),
                       driver / 1000, (driver % 1000) / 10);
}

}  // namespace npt::nerf::cuda
