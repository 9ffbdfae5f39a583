#include "nerf/cuda/cuda_field.h"

#include <numeric>

#include "core/cuda/device_buffer.h"
#include "nerf/cuda/adam_kernels.h"
#include "nerf/cuda/cuda_device.h"
#include "nerf/cuda/fused_mlp.h"
#include "nerf/cuda/hash_grid_kernels.h"

namespace npt::nerf::cuda {

namespace {

__global__ void field_query_kernel(NerfFieldView field, const Vec3* pos, const Vec3* dirs, uint32_t n,
                                   float* sigma, Rgb* rgb) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    if (dirs)
        field.query(pos[i], dirs[i], &sigma[i], &rgb[i]);
    else
        sigma[i] = field.density(pos[i]);
}

}  // namespace

void evaluate_field(const NerfModel& model, const std::vector<Vec3>& positions, const std::vector<Vec3>& dirs,
                    Precision precision, std::vector<float>& sigma, std::vector<Rgb>& rgb) {
    require_cuda_device();
    const bool with_color = !dirs.empty();
    if (with_color && dirs.size() != positions.size())
        throw Error("evaluate_field: " + std::to_string(dirs.size()) + " directions for " +
                    std::to_string(positions.size()) + " points");
    const NerfLayout layout = model.layout();
    const uint32_t n = uint32_t(positions.size());
    sigma.assign(n, 0.0f);
    if (with_color) rgb.assign(n, Rgb(0.0f));
    if (n == 0) return;
    // Whole MLP tiles: the fused kernels may touch every row of the last one.
    const uint32_t rows = (n + k_mlp_rows_per_tile - 1) / k_mlp_rows_per_tile * k_mlp_rows_per_tile;
    gpu::DeviceBuffer<float> params(model.params);
    gpu::DeviceBuffer<Vec3> d_pos(rows, "the points"), d_dir;
    gpu::cuda_check(cudaMemcpy(d_pos.data(), positions.data(), n * sizeof(Vec3), cudaMemcpyHostToDevice),
                    "cudaMemcpy");
    if (with_color) d_dir.upload(dirs);
    gpu::DeviceBuffer<float> d_sigma(rows, "the densities");
    gpu::DeviceBuffer<Rgb> d_rgb(with_color ? rows : 0, "the colours");
    if (precision == Precision::fp32) {
        const NerfFieldView field(layout, params.data());
        field_query_kernel<<<(n + 127) / 128, 128>>>(field, d_pos.data(), with_color ? d_dir.data() : nullptr, n,
                                                     d_sigma.data(), d_rgb.data());
        NPT_CUDA_CHECK_LAUNCH("field_query_kernel");
    } else {
        std::string why;
        if (!mlp_shape_supported(layout, &why)) throw Error("evaluate_field (fp16): " + why);
        gpu::DeviceBuffer<__half> half_w(k_mlp_half_weights), enc(size_t(rows) * k_mlp_inputs, "the encodings");
        gpu::cuda_check(cudaMemset(half_w.data(), 0, half_w.bytes()), "cudaMemset");
        to_half(params.data(), uint32_t(k_mlp_param_count), half_w.data(), nullptr);
        std::vector<uint32_t> identity(n);
        std::iota(identity.begin(), identity.end(), 0u);
        gpu::DeviceBuffer<uint32_t> ray_of(identity);
        HashGridArgs h;
        h.layout = layout;
        h.positions = d_pos.data();
        h.n_host = n;
        h.capacity = rows;
        hash_encode(h, params.data() + layout.grid_offset, enc.data(), nullptr);
        MlpInferenceArgs a;
        a.weights = half_w.data();
        a.encoded = enc.data();
        a.sample_ray = ray_of.data();
        a.ray_dir = with_color ? d_dir.data() : nullptr;
        a.n_host = n;
        a.capacity = rows;
        a.sigma = d_sigma.data();
        a.rgb = d_rgb.data();
        mlp_inference(a, !with_color, nullptr);
    }
    gpu::cuda_check(cudaDeviceSynchronize(), "evaluating the field");
    gpu::cuda_check(cudaMemcpy(sigma.data(), d_sigma.data(), n * sizeof(float), cudaMemcpyDeviceToHost), "cudaMemcpy");
    if (with_color)
        gpu::cuda_check(cudaMemcpy(rgb.data(), d_rgb.data(), n * sizeof(Rgb), cudaMemcpyDeviceToHost), "cudaMemcpy");
}

}  // namespace npt::nerf::cuda
