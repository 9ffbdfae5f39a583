// Kernels that run the shared NPT_HD math (BSDFs, lights, camera) on the GPU for the CPU-vs-GPU parity test.
// Compiling this file is also what makes host-only code in those headers a build error wherever nvcc exists.
#include <vector>

#include "core/sobol_sampler.h"
#include "lights/light.h"
#include "materials/bsdf.h"
#include "nerf/composite.h"
#include "nerf/hash_encoding.h"
#include "nerf/nerf_model.h"
#include "nerf/ray_march.h"
#include "nerf/sh_encoding.h"
#include "render/camera.h"
#include "core/cuda/device_buffer.h"
#include "render/gpu/device_scene.h"
#include "render/gpu/shared_math_check.h"

namespace npt::gpu {

namespace {

constexpr int k_block = 128;
int blocks_for(size_t n) { return int((n + k_block - 1) / k_block); }

__global__ void bsdf_kernel(const BsdfCase* cases, BsdfResult* out, size_t n) {
    size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const BsdfCase& c = cases[i];
    BsdfResult r;
    r.f = materials::bsdf_eval(c.bsdf, c.wo, c.wi);
    r.pdf = materials::bsdf_pdf(c.bsdf, c.wo, c.wi);
    r.sample = materials::BsdfSample{};
    r.sampled = materials::bsdf_sample(c.bsdf, c.wo, c.u_lobe, c.u, &r.sample);
    out[i] = r;
}

__global__ void camera_kernel(render::CameraView cam, const CameraCase* cases, Ray* out, size_t n) {
    size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    out[i] = render::generate_camera_ray(cam, cases[i].i, cases[i].j, cases[i].u);
}

__global__ void light_kernel(lights::LightSetView ls, const LightCase* cases, LightResult* out, size_t n) {
    size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    LightResult r;
    r.sample = lights::LightSample{};
    r.sampled = lights::sample_light(ls, cases[i].ref_p, cases[i].u_select, cases[i].u, &r.sample);
    out[i] = r;
}

__global__ void sampler_kernel(uint64_t seed, int dims, const SamplerCase* cases, Vec2* out, size_t n) {
    size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    SobolSampler s(seed, cases[i].px, cases[i].py, cases[i].sample);
    for (int d = 0; d < dims; ++d) out[i * size_t(dims) + size_t(d)] = s.next_2d();
}

__global__ void volume_kernel(Span<const media::VolumeView> volumes, const VolumeCase* cases,
                              media::VolumeResult* out, size_t n) {
    size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const VolumeCase& c = cases[i];
    out[i] = media::integrate_volumes(volumes, c.ray, 0.0f, c.t_end, c.xi, c.shadow);
}

void check_launch(const char* what) {
    cuda_check(cudaGetLastError(), what);
    cuda_check(cudaDeviceSynchronize(), what);
}

}  // namespace

// Not launched yet: compiling it keeps the NeRF encodings device-clean until the CUDA trainer (issue 5) uses them.
__global__ void nerf_encoding_kernel(nerf::HashGridConfig cfg, const float* params, const Vec3* points, float* out,
                                     float* d_params, size_t n) {
    size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    float features[64];
    nerf::hash_encode(cfg, params, points[i], features);
    nerf::hash_encode_backward(cfg, points[i], features, d_params);
    nerf::sh_encode_deg4(normalize(points[i]), out + i * nerf::k_sh_deg4_dims);
}

// Not launched yet: compiles the occupancy-grid march and the compositing for the device until the CUDA
// trainer uses them. One thread per ray; samples and gradients go to per-ray slices of max_samples.
__global__ void nerf_march_composite_kernel(nerf::MarchParams mp, nerf::OccupancyGridView grid,
                                            const Ray* rays, nerf::MarchSample* samples, const float* sigma,
                                            const Rgb* rgb, float* dt, Rgb* color, float* d_sigma, Rgb* d_rgb,
                                            size_t n) {
    size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const size_t base = i * size_t(mp.max_samples);
    const int count = nerf::march_ray(mp, grid, rays[i], 0.5f, samples + base);
    for (int k = 0; k < count; ++k) dt[base + k] = samples[base + k].dt;
    const nerf::CompositeResult fwd =
        nerf::composite_forward(sigma + base, rgb + base, dt + base, count, 1e-4f, Rgb(1.0f));
    color[i] = fwd.color;
    nerf::composite_backward(sigma + base, rgb + base, dt + base, count, fwd, Rgb(1.0f), Rgb(1.0f),
                             d_sigma + base, d_rgb + base);
}

// The per-point field query the path tracer will run on the GPU (issue 6); compiled here so that host-only code
// in the NeRF headers fails the CUDA build. Not launched yet.
__global__ void nerf_field_kernel(nerf::NerfFieldView field, const Vec3* points, float* sigma, Rgb* rgb,
                                  size_t n) {
    size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    field.query(points[i], normalize(points[i] - Vec3(0.5f)), sigma + i, rgb + i);
}

bool device_available() {
    int count = 0;
    return cudaGetDeviceCount(&count) == cudaSuccess && count > 0;
}

std::vector<BsdfResult> run_bsdf_cases(const std::vector<BsdfCase>& cases) {
    DeviceBuffer<BsdfCase> in(cases);
    DeviceBuffer<BsdfResult> out(cases.size());
    if (!cases.empty()) bsdf_kernel<<<blocks_for(cases.size()), k_block>>>(in.data(), out.data(), cases.size());
    check_launch("bsdf_kernel");
    return out.download();
}

std::vector<Ray> run_camera_cases(const render::CameraView& camera, const std::vector<CameraCase>& cases) {
    DeviceBuffer<CameraCase> in(cases);
    DeviceBuffer<Ray> out(cases.size());
    if (!cases.empty()) camera_kernel<<<blocks_for(cases.size()), k_block>>>(camera, in.data(), out.data(), cases.size());
    check_launch("camera_kernel");
    return out.download();
}

std::vector<Vec2> run_sampler_cases(uint64_t seed, int dimensions, const std::vector<SamplerCase>& cases) {
    DeviceBuffer<SamplerCase> in(cases);
    DeviceBuffer<Vec2> out(cases.size() * size_t(dimensions));
    if (!cases.empty())
        sampler_kernel<<<blocks_for(cases.size()), k_block>>>(seed, dimensions, in.data(), out.data(), cases.size());
    check_launch("sampler_kernel");
    return out.download();
}

std::vector<media::VolumeResult> run_volume_cases(const std::vector<media::VolumeView>& volumes,
                                                  const std::vector<VolumeCase>& cases) {
    const DeviceVolumes device({volumes.data(), volumes.size()});
    DeviceBuffer<VolumeCase> in(cases);
    DeviceBuffer<media::VolumeResult> out(cases.size());
    if (!cases.empty())
        volume_kernel<<<blocks_for(cases.size()), k_block>>>(device.view(), in.data(), out.data(), cases.size());
    check_launch("volume_kernel");
    return out.download();
}

std::vector<LightResult> run_light_cases(const lights::LightSetView& lights, const std::vector<LightCase>& cases) {
    DeviceLightSet device(lights);
    DeviceBuffer<LightCase> in(cases);
    DeviceBuffer<LightResult> out(cases.size());
    if (!cases.empty())
        light_kernel<<<blocks_for(cases.size()), k_block>>>(device.view(), in.data(), out.data(), cases.size());
    check_launch("light_kernel");
    return out.download();
}

}  // namespace npt::gpu
