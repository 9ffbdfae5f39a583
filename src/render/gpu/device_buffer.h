// RAII ownership of device memory (cudaMalloc/cudaFree; no managed memory), and the error check every CUDA
// call goes through. Host code compiled by nvcc only.
#pragma once

#include <cuda_runtime.h>

#include <string>
#include <vector>

#include "core/error.h"

namespace npt::gpu {

inline void cuda_check(cudaError_t e, const char* what) {
    if (e != cudaSuccess) throw Error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(e));
}

template <typename T>
class DeviceBuffer {
  public:
    DeviceBuffer() = default;
    explicit DeviceBuffer(size_t n) { allocate(n); }
    explicit DeviceBuffer(const std::vector<T>& host) { upload(host.data(), host.size()); }
    DeviceBuffer(const T* host, size_t n) { upload(host, n); }
    ~DeviceBuffer() { cudaFree(m_ptr); }
    DeviceBuffer(const DeviceBuffer&) = delete;
    DeviceBuffer& operator=(const DeviceBuffer&) = delete;
    DeviceBuffer(DeviceBuffer&& o) noexcept : m_ptr(o.m_ptr), m_size(o.m_size) {
        o.m_ptr = nullptr, o.m_size = 0;
    }
    DeviceBuffer& operator=(DeviceBuffer&& o) noexcept {
        std::swap(m_ptr, o.m_ptr);
        std::swap(m_size, o.m_size);
        return *this;
    }

    void allocate(size_t n) {
        cudaFree(m_ptr);
        m_ptr = nullptr;
        m_size = n;
        if (n) cuda_check(cudaMalloc(&m_ptr, n * sizeof(T)), "cudaMalloc");
    }
    void upload(const T* host, size_t n) {
        allocate(n);
        if (n)
            cuda_check(cudaMemcpy(m_ptr, host, n * sizeof(T), cudaMemcpyHostToDevice),
                       "cudaMemcpy to device");
    }
    std::vector<T> download() const {
        std::vector<T> host(m_size);
        if (m_size)
            cuda_check(cudaMemcpy(host.data(), m_ptr, m_size * sizeof(T), cudaMemcpyDeviceToHost),
                       "cudaMemcpy to host");
        return host;
    }
    T* data() const { return m_ptr; }
    size_t size() const { return m_size; }

  private:
    T* m_ptr = nullptr;
    size_t m_size = 0;
};

}  // namespace npt::gpu
