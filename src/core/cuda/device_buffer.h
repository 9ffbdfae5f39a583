// RAII ownership of device memory (plain cudaMalloc/cudaFree; no managed memory) and the error checks every CUDA
// call and kernel launch go through. An allocation that does not fit says how much it asked for, how much is
// free, and which setting lowers it, on one line. Host code only (compiled by nvcc or by g++ with the CUDA
// runtime headers).
#pragma once

#include <cuda_runtime.h>

#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"

namespace npt::gpu {

inline void cuda_check(cudaError_t e, const char* what) {
    if (e != cudaSuccess) throw Error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(e));
}

// After a kernel launch: a bad configuration shows here; faults inside the kernel show at the next sync.
#define NPT_CUDA_CHECK_LAUNCH(kernel_name) ::npt::gpu::cuda_check(cudaGetLastError(), "launching " kernel_name)

inline std::string format_mib(size_t bytes) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.1f MiB", double(bytes) / (1024.0 * 1024.0));
    return buf;
}

// Throws the out-of-memory message: `what` names the buffer, `lower` the option or setting that shrinks it.
[[noreturn]] inline void throw_out_of_memory(size_t bytes, const char* what, const char* lower) {
    cudaGetLastError();  // clear the sticky allocation error so that later calls work
    size_t free_bytes = 0, total_bytes = 0;
    cudaMemGetInfo(&free_bytes, &total_bytes);
    std::string msg = "GPU out of memory: " + std::string(what ? what : "a buffer") + " needs " +
                      format_mib(bytes) + " but only " + format_mib(free_bytes) + " of " +
                      format_mib(total_bytes) + " are free";
    if (lower && *lower) msg += "; lower " + std::string(lower);
    throw Error(msg);
}

template <typename T>
class DeviceBuffer {
  public:
    DeviceBuffer() = default;
    explicit DeviceBuffer(size_t n, const char* what = nullptr, const char* lower = nullptr) {
        allocate(n, what, lower);
    }
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

    // Discards the old contents. `what`/`lower` make the out-of-memory error say which buffer and which
    // setting to lower.
    void allocate(size_t n, const char* what = nullptr, const char* lower = nullptr) {
        cudaFree(m_ptr);
        m_ptr = nullptr;
        m_size = 0;
        if (n == 0) return;
        const cudaError_t e = cudaMalloc(&m_ptr, n * sizeof(T));
        if (e == cudaErrorMemoryAllocation) {
            m_ptr = nullptr;
            throw_out_of_memory(n * sizeof(T), what, lower);
        }
        cuda_check(e, "cudaMalloc");
        m_size = n;
    }
    void upload(const T* host, size_t n, const char* what = nullptr, const char* lower = nullptr) {
        if (n != m_size) allocate(n, what, lower);
        if (n)
            cuda_check(cudaMemcpy(m_ptr, host, n * sizeof(T), cudaMemcpyHostToDevice),
                       "cudaMemcpy to device");
    }
    void upload(const std::vector<T>& host, const char* what = nullptr, const char* lower = nullptr) {
        upload(host.data(), host.size(), what, lower);
    }
    std::vector<T> download() const {
        std::vector<T> host(m_size);
        download_to(host.data());
        return host;
    }
    void download_to(T* host) const {
        if (m_size)
            cuda_check(cudaMemcpy(host, m_ptr, m_size * sizeof(T), cudaMemcpyDeviceToHost),
                       "cudaMemcpy to host");
    }
    void zero_async(cudaStream_t stream) const {
        if (m_size) cuda_check(cudaMemsetAsync(m_ptr, 0, m_size * sizeof(T), stream), "cudaMemsetAsync");
    }
    T* data() const { return m_ptr; }
    size_t size() const { return m_size; }
    size_t bytes() const { return m_size * sizeof(T); }

  private:
    T* m_ptr = nullptr;
    size_t m_size = 0;
};

}  // namespace npt::gpu
