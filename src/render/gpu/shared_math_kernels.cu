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

template <typename T>
Span<const T> span_of(const DeviceBuffer<T>& b) {
    return {b.data(), b.size()};
}

// Owns device copies of every array a LightSetView points to, and the view over them.
class DeviceLightSet {
public:
    explicit DeviceLightSet(const lights::LightSetView& host) : m_view(host) {
        m_lights.upload(host.lights.data, host.lights.size);
        m_bins.upload(host.selector.bins.data, host.selector.bins.size);
        m_offsets.upload(host.mesh_light_offset.data, host.mesh_light_offset.size);
        std::vector<TextureView> textures;
        for (size_t t = 0; t < host.textures.size; ++t) textures.push_back(upload_texture(host.textures[t]));
        m_textures.upload(textures.data(), textures.size());
        m_view.lights = span_of(m_lights);
        m_view.selector.bins = span_of(m_bins);
        m_view.mesh_light_offset = span_of(m_offsets);
        m_view.textures = span_of(m_textures);

        const Distribution2DView& d = host.environment.distribution;
        m_env_texture_view = upload_texture(host.environment.texture);
        m_view.environment.texture = m_env_texture_view;
        m_func.upload(d.func.data, d.func.size);
        m_conditional.upload(d.conditional.data, d.conditional.size);
        m_marginal.upload(d.marginal_cdf.data, d.marginal_cdf.size);
        m_view.environment.distribution.func = span_of(m_func);
        m_view.environment.distribution.conditional = span_of(m_conditional);
        m_view.environment.distribution.marginal_cdf = span_of(m_marginal);
    }
    const lights::LightSetView& view() const { return m_view; }

private:
    TextureView upload_texture(const TextureView& t) {
        if (!t.valid()) return TextureView{};
        m_texels.emplace_back(t.rgba, size_t(t.width) * size_t(t.height) * 4);
        return TextureView{m_texels.back().data(), t.width, t.height};
    }

    lights::LightSetView m_view;
    DeviceBuffer<lights::Light> m_lights;
    DeviceBuffer<AliasBin> m_bins;
    DeviceBuffer<int32_t> m_offsets;
    DeviceBuffer<TextureView> m_textures;
    std::vector<DeviceBuffer<float>> m_texels;
    TextureView m_env_texture_view;
    DeviceBuffer<float> m_func, m_conditional, m_marginal;
};

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
    std::vector<DeviceBuffer<float>> densities, majorants;
    std::vector<DeviceBuffer<Vec3>> colors;
    std::vector<media::VolumeView> device_views = volumes;
    std::vector<DeviceBuffer<uint8_t>> occupancies;
    for (media::VolumeView& v : device_views) {
        if (v.kind == media::VolumeKind::Nerf) {
            // The network's parameters and the occupancy bytes; everything else in the view is plain values.
            densities.emplace_back(v.nerf.field.params, v.nerf.field.layout.total);
            v.nerf.field.params = densities.back().data();
            const size_t r = size_t(v.nerf.occupancy.resolution);
            occupancies.emplace_back(v.nerf.occupancy.occupied, size_t(v.nerf.occupancy.cascades) * r * r * r);
            v.nerf.occupancy.occupied = occupancies.back().data();
            continue;
        }
        size_t n = size_t(v.grid.nx) * size_t(v.grid.ny) * size_t(v.grid.nz);
        densities.emplace_back(v.grid.density, n);
        colors.emplace_back(v.grid.color, n);
        v.grid.density = densities.back().data();
        v.grid.color = colors.back().data();
        if (v.majorant.max_density) {
            size_t m = size_t(v.majorant.nx) * size_t(v.majorant.ny) * size_t(v.majorant.nz);
            majorants.emplace_back(v.majorant.max_density, m);
            v.majorant.max_density = majorants.back().data();
        }
    }
    DeviceBuffer<media::VolumeView> views(device_views);
    DeviceBuffer<VolumeCase> in(cases);
    DeviceBuffer<media::VolumeResult> out(cases.size());
    if (!cases.empty())
        volume_kernel<<<blocks_for(cases.size()), k_block>>>({views.data(), views.size()}, in.data(), out.data(),
                                                            cases.size());
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
