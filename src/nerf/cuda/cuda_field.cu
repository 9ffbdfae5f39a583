#include "nerf/cuda/cuda_field.h"

#include <algorithm>
#include <numeric>

#include "core/cuda/device_buffer.h"
#include "nerf/cuda/adam_kernels.h"
#include "nerf/cuda/cuda_device.h"
#include "nerf/cuda/fused_mlp.h"
#include "nerf/cuda/hash_grid_kernels.h"

namespace npt::nerf::cuda {

namespace {

constexpr uint32_t k_chunk = 1u << 21;  // points per launch

__global__ void field_query_kernel(NerfFieldView field, const Vec3* pos, const Vec3* dirs, uint32_t n,
                                   float* sigma, Rgb* rgb) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    if (dirs)
        field.query(pos[i], dirs[i], &sigma[i], &rgb[i]);
    else
        sigma[i] = field.density(pos[i]);
}

__global__ void iota_kernel(uint32_t* out, uint32_t n) {
    const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i < n) out[i] = i;
}

}  // namespace

struct CudaFieldEvaluator::Impl {
    Precision precision;
    NerfLayout layout;
    gpu::DeviceBuffer<float> params;
    gpu::DeviceBuffer<__half> half_w, enc;
    gpu::DeviceBuffer<uint32_t> identity;
    gpu::DeviceBuffer<Vec3> pos, dir;
    gpu::DeviceBuffer<float> sigma;
    gpu::DeviceBuffer<Rgb> rgb;
};

CudaFieldEvaluator::CudaFieldEvaluator(const NerfModel& model, Precision precision)
    : m(std::make_unique<Impl>()) {
    require_cuda_device();
    m->precision = precision;
    m->layout = model.layout();
    if (model.params.size() != m->layout.total) throw Error("the model's parameters do not match its layout");
    std::string why;
    if (precision == Precision::fp16 && !mlp_shape_supported(m->layout, &why))
        throw Error("the fp16 field kernels do not support this model's network (" + why + ")");
    m->params.upload(model.params, "the model parameters", "encoding.log2_table_size");
    // Whole MLP tiles: the fused kernels may read every row of the last one.
    m->pos.allocate(k_chunk, "the points");
    m->dir.allocate(k_chunk, "the points");
    m->sigma.allocate(k_chunk, "the points");
    m->rgb.allocate(k_chunk, "the points");
    if (precision == Precision::fp16) {
        m->half_w.allocate(k_mlp_half_weights);
        gpu::cuda_check(cudaMemset(m->half_w.data(), 0, m->half_w.bytes()), "cudaMemset");
        to_half(m->params.data(), uint32_t(k_mlp_param_count), m->half_w.data(), nullptr);
        m->enc.allocate(size_t(k_chunk) * k_mlp_inputs, "the encodings");
        m->identity.allocate(k_chunk);
        iota_kernel<<<(k_chunk + 255) / 256, 256>>>(m->identity.data(), k_chunk);
        NPT_CUDA_CHECK_LAUNCH("iota_kernel");
    }
}

CudaFieldEvaluator::~CudaFieldEvaluator() = default;

void CudaFieldEvaluator::evaluate(const Vec3* positions, const Vec3* dirs, size_t total, float* sigma_out,
                                  Rgb* rgb_out) {
    Impl& I = *m;
    for (size_t off = 0; off < total; off += k_chunk) {
        const uint32_t n = uint32_t(std::min<size_t>(k_chunk, total - off));
        gpu::cuda_check(cudaMemcpy(I.pos.data(), positions + off, n * sizeof(Vec3), cudaMemcpyHostToDevice),
                        "cudaMemcpy");
        if (dirs)
            gpu::cuda_check(cudaMemcpy(I.dir.data(), dirs + off, n * sizeof(Vec3), cudaMemcpyHostToDevice),
                            "cudaMemcpy");
        if (I.precision == Precision::fp32) {
            const NerfFieldView field(I.layout, I.params.data());
            field_query_kernel<<<(n + 127) / 128, 128>>>(field, I.pos.data(), dirs ? I.dir.data() : nullptr, n,
                                                         I.sigma.data(), I.rgb.data());
            NPT_CUDA_CHECK_LAUNCH("field_query_kernel");
        } else {
            HashGridArgs h;
            h.layout = I.layout;
            h.positions = I.pos.data();
            h.n_host = n;
            h.capacity = k_chunk;
            hash_encode(h, I.params.data() + I.layout.grid_offset, I.enc.data(), nullptr);
            MlpInferenceArgs a;
            a.weights = I.half_w.data();
            a.encoded = I.enc.data();
            a.sample_ray = I.identity.data();
            a.ray_dir = dirs ? I.dir.data() : nullptr;
            a.n_host = n;
            a.capacity = k_chunk;
            a.sigma = I.sigma.data();
            a.rgb = I.rgb.data();
            mlp_inference(a, dirs == nullptr, nullptr);
        }
        gpu::cuda_check(cudaDeviceSynchronize(), "evaluating the field");
        gpu::cuda_check(cudaMemcpy(sigma_out + off, I.sigma.data(), n * sizeof(float), cudaMemcpyDeviceToHost),
                        "cudaMemcpy");
        if (dirs)
            gpu::cuda_check(cudaMemcpy(rgb_out + off, I.rgb.data(), n * sizeof(Rgb), cudaMemcpyDeviceToHost),
                            "cudaMemcpy");
    }
}

void evaluate_field(const NerfModel& model, const std::vector<Vec3>& positions, const std::vector<Vec3>& dirs,
                    Precision precision, std::vector<float>& sigma, std::vector<Rgb>& rgb) {
    const bool with_color = !dirs.empty();
    if (with_color && dirs.size() != positions.size())
        throw Error("evaluate_field: " + std::to_string(dirs.size()) + " directions for " +
                    std::to_string(positions.size()) + " points");
    sigma.assign(positions.size(), 0.0f);
    if (with_color) rgb.assign(positions.size(), Rgb(0.0f));
    if (positions.empty()) return;
    CudaFieldEvaluator e(model, precision);
    e.evaluate(positions.data(), with_color ? dirs.data() : nullptr, positions.size(), sigma.data(),
               with_color ? rgb.data() : nullptr);
}

}  // namespace npt::nerf::cuda
