#include "nerf/cuda/cuda_renderer.h"

#include <cuda_runtime.h>

#include <algorithm>
#include <vector>

#include "core/cuda/device_buffer.h"
#include "core/error.h"
#include "nerf/cuda/adam_kernels.h"
#include "nerf/cuda/cuda_device.h"
#include "nerf/cuda/fused_mlp.h"
#include "nerf/cuda/occupancy_bits.h"
#include "nerf/cuda/render_kernels.h"
#include "nerf/cuda/sample_slots.h"

namespace npt::nerf::cuda {

using gpu::cuda_check;
using gpu::DeviceBuffer;

namespace {
constexpr uint32_t k_max_slots = 1u << 22;  // samples evaluated per round at most
constexpr int k_first_round = 8;            // samples per live ray in the first round; doubles every round
constexpr int k_max_round = 64;
}  // namespace

struct CudaViewRenderer::Impl {
    const NerfModel& model;
    Precision precision;
    std::string device;
    NerfLayout layout;
    MarchParams march;
    Vec3 box_min, box_max;  // around the occupied cells
    cudaStream_t stream = nullptr;
    DeviceBuffer<float> params;
    DeviceBuffer<__half> mlp_half;
    DeviceBuffer<uint32_t> occupied, coarse;  // bit fields (OccupancyGridView)
    // Per frame (resized with the image).
    int width = 0, height = 0;
    DeviceBuffer<RenderRay> rays;
    DeviceBuffer<Vec3> dirs;
    DeviceBuffer<float4> image;
    DeviceBuffer<uint32_t> alive[2], counts;
    // Per round.
    SampleSlotBuffers slots;
    uint32_t* host_count = nullptr;

    Impl(const NerfModel& m, Precision p) : model(m), precision(p) {}
    ~Impl() {
        if (host_count) cudaFreeHost(host_count);
        if (stream) cudaStreamDestroy(stream);
    }
    void resize(int w, int h);
    void run(const Camera& camera, const ViewOptions& options);
    uint32_t read_count(int which);
};

void CudaViewRenderer::Impl::resize(int w, int h) {
    if (w == width && h == height) return;
    const size_t n = size_t(w) * size_t(h);
    rays.allocate(n, "the per-pixel ray state", "--res");
    dirs.allocate(n, "the per-pixel ray state", "--res");
    image.allocate(n, "the image", "--res");
    alive[0].allocate(n, "the per-pixel ray state", "--res");
    alive[1].allocate(n, "the per-pixel ray state", "--res");
    // At least one sample slot per pixel, so that every live ray takes part in every round.
    const size_t capacity = std::max<size_t>(k_max_slots, (n + 127) / 128 * 128);
    if (capacity != slots.capacity())
        slots.allocate(capacity, capacity, precision == Precision::fp16, "the sample slots", "--res");
    width = w;
    height = h;
}

uint32_t CudaViewRenderer::Impl::read_count(int which) {
    cuda_check(
        cudaMemcpyAsync(host_count, counts.data() + which, sizeof(uint32_t), cudaMemcpyDeviceToHost, stream),
        "cudaMemcpyAsync");
    cuda_check(cudaStreamSynchronize(stream), "rendering");
    return *host_count;
}

void CudaViewRenderer::Impl::run(const Camera& camera, const ViewOptions& options) {
    if (camera.width <= 0 || camera.height <= 0) throw Error("render_view: the camera has no pixels");
    resize(camera.width, camera.height);
    RenderFrame f;
    f.rays = rays.data();
    f.dirs = dirs.data();
    f.image = image.data();
    f.width = width;
    f.height = height;
    f.background = options.background;
    f.march = march;
    f.grid = {nullptr, model.occupancy.cascades(), model.occupancy.resolution(), occupied.data(),
              coarse.size() ? coarse.data() : nullptr};
    f.min_transmittance = model.config.march.min_transmittance;
    f.box_min = box_min;
    f.box_max = box_max;
    f.object = view_object_cut(model, options);
    const RenderSlots round = slots.view(counts.data() + 2);

    cuda_check(cudaMemsetAsync(counts.data(), 0, 3 * sizeof(uint32_t), stream), "cudaMemsetAsync");
    render_init(f, make_ray_camera(camera, model.world_to_model), alive[0].data(), counts.data(), stream);
    uint32_t n = read_count(0);
    int cur = 0;
    const uint32_t capacity = uint32_t(slots.capacity());  // >= one slot per pixel (resize)
    const int first =
        options.gpu_first_round > 0 ? std::min(options.gpu_first_round, k_max_round) : k_first_round;
    for (int k = first; n > 0; k = std::min(2 * k, k_max_round)) {
        const int kk = int(std::max<uint32_t>(1, std::min<uint32_t>(uint32_t(k), capacity / n)));
        const uint32_t m = n * uint32_t(kk);  // samples this round at most
        cuda_check(cudaMemsetAsync(round.count, 0, sizeof(uint32_t), stream), "cudaMemsetAsync");
        render_march(f, alive[cur].data(), n, kk, round, stream);
        if (precision == Precision::fp32) {
            const NerfFieldView field(layout, params.data());
            render_field_fp32(field, round, dirs.data(), m, slots.sigma.data(), slots.rgb.data(), stream);
        } else {
            render_field_fp16(layout, params.data(), mlp_half.data(), round, dirs.data(),
                              field_rows(m, capacity), slots.encoded.data(), slots.sigma.data(),
                              slots.rgb.data(), stream);
        }
        const int nxt = 1 - cur;
        cuda_check(cudaMemsetAsync(counts.data() + nxt, 0, sizeof(uint32_t), stream), "cudaMemsetAsync");
        render_composite(f, alive[cur].data(), n, kk, round, slots.sigma.data(), slots.rgb.data(),
                         alive[nxt].data(), counts.data() + nxt, stream);
        n = read_count(nxt);
        cur = nxt;
    }
}

CudaViewRenderer::CudaViewRenderer(const NerfModel& model, Precision precision)
    : m(std::make_unique<Impl>(model, precision)) {
    Impl& I = *m;
    I.device = require_cuda_device();
    I.layout = model.layout();
    std::string why;
    if (precision == Precision::fp16 && !mlp_shape_supported(I.layout, &why))
        throw Error("the CUDA renderer's fp16 kernels do not support this model's network (" + why +
                    "); use --backend cpu");
    if (model.params.size() != I.layout.total) throw Error("the model's parameters do not match its layout");
    I.march = model.march_params();
    cuda_check(cudaStreamCreate(&I.stream), "cudaStreamCreate");
    I.params.upload(model.params, "the model parameters", "encoding.log2_table_size");
    if (precision == Precision::fp16) {
        I.mlp_half.allocate(k_mlp_half_weights);
        cuda_check(cudaMemset(I.mlp_half.data(), 0, I.mlp_half.bytes()), "cudaMemset");
        to_half(I.params.data(), uint32_t(k_mlp_param_count), I.mlp_half.data(), I.stream);
    }
    // The marches read the occupancy as bit fields, inside the box around the occupied cells.
    const OccupancyBits bits = occupancy_bits(model.occupancy.view());
    I.occupied.upload(bits.occupied, "the occupancy grid", "occupancy.resolution");
    if (!bits.coarse.empty()) I.coarse.upload(bits.coarse, "the occupancy grid", "occupancy.resolution");
    I.box_min = bits.box_min;
    I.box_max = bits.box_max;
    I.counts.allocate(3);  // live rays (two lists), samples of the round
    cuda_check(cudaMallocHost(&I.host_count, sizeof(uint32_t)), "cudaMallocHost");
    cuda_check(cudaStreamSynchronize(I.stream), "uploading the model");
}

CudaViewRenderer::~CudaViewRenderer() = default;

std::string CudaViewRenderer::device_name() const { return m->device; }

Image CudaViewRenderer::render(const Camera& camera, const ViewOptions& options) {
    m->run(camera, options);
    std::vector<float4> px = m->image.download();
    Image img(camera.width, camera.height, 4);
    for (size_t i = 0; i < px.size(); ++i) {
        img.pixels[4 * i + 0] = px[i].x;
        img.pixels[4 * i + 1] = px[i].y;
        img.pixels[4 * i + 2] = px[i].z;
        img.pixels[4 * i + 3] = px[i].w;
    }
    return img;
}

double CudaViewRenderer::render_timed(const Camera& camera, const ViewOptions& options) {
    cudaEvent_t start, stop;
    cuda_check(cudaEventCreate(&start), "cudaEventCreate");
    cuda_check(cudaEventCreate(&stop), "cudaEventCreate");
    cuda_check(cudaEventRecord(start, m->stream), "cudaEventRecord");
    m->run(camera, options);
    cuda_check(cudaEventRecord(stop, m->stream), "cudaEventRecord");
    cuda_check(cudaEventSynchronize(stop), "cudaEventSynchronize");
    float ms = 0;
    cudaEventElapsedTime(&ms, start, stop);
    cudaEventDestroy(start);
    cudaEventDestroy(stop);
    return double(ms);
}

}  // namespace npt::nerf::cuda
