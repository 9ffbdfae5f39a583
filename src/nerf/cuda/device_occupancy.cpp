#include "nerf/cuda/device_occupancy.h"

#include <algorithm>
#include <vector>

#include "nerf/cuda/fused_mlp.h"
#include "nerf/cuda/hash_grid_kernels.h"

namespace npt::nerf::cuda {

namespace {
constexpr uint32_t k_max_chunk = 1u << 21;  // points evaluated per launch during an update
}

DeviceOccupancy::DeviceOccupancy(const OccupancyGrid& host, float threshold, cudaStream_t s) {
    const std::vector<float>& d = host.density();
    m_density.upload(d, "the occupancy grid", "occupancy.resolution");
    m_estimate.allocate(d.size(), "the occupancy grid", "occupancy.resolution");
    m_occupied.allocate(d.size(), "the occupancy grid", "occupancy.resolution");
    m_list.allocate(d.size(), "the occupancy grid", "occupancy.resolution");
    m_bits.allocate((d.size() + 31) / 32, "the occupancy grid", "occupancy.resolution");
    m_count.allocate(1);
    m_sum.allocate(1);
    m_estimate.zero_async(s);
    m_dev.density = m_density.data();
    m_dev.estimate = m_estimate.data();
    m_dev.occupied = m_occupied.data();
    m_dev.occupied_bits = m_bits.data();
    m_box.allocate(6);
    m_dev.occupied_box = m_box.data();
    if (coarse_cells_fit(host.resolution())) {
        m_coarse.allocate(coarse_words(host.cascades(), host.resolution()), "the occupancy grid");
        m_dev.coarse_bits = m_coarse.data();
    }
    m_dev.occupied_list = m_list.data();
    m_dev.occupied_count = m_count.data();
    m_dev.density_sum = m_sum.data();
    m_dev.cascades = host.cascades();
    m_dev.resolution = host.resolution();
    m_dev.cells = uint32_t(d.size());
    m_chunk = std::min<uint32_t>(k_max_chunk, m_dev.cells);
    // Rounded up to whole MLP tiles: the kernels may touch every row of the last tile.
    const uint32_t rows = (m_chunk + k_mlp_rows_per_tile - 1) / k_mlp_rows_per_tile * k_mlp_rows_per_tile;
    m_plan_cells.allocate(rows, "occupancy update points", "occupancy.resolution");
    m_plan_pos.allocate(rows, "occupancy update points", "occupancy.resolution");
    m_plan_enc.allocate(size_t(rows) * k_mlp_inputs, "occupancy update points", "occupancy.resolution");
    m_plan_sigma.allocate(rows, "occupancy update points", "occupancy.resolution");
    // decay 1 with no estimates keeps every density and derives the flags and the occupied list.
    occupancy_apply(m_dev, 1.0f, threshold, s);
}

void DeviceOccupancy::update(const OccupancyConfig& cfg, const NerfLayout& layout, const float* grid_params,
                             const __half* mlp_half, bool warmup, uint64_t seed, float min_step,
                             cudaStream_t s) {
    const uint32_t total = warmup ? m_dev.cells : 2 * std::max<uint32_t>(1, m_dev.cells / 4);
    for (uint32_t first = 0; first < total; first += m_chunk) {
        const uint32_t n = std::min(m_chunk, total - first);
        occupancy_plan(m_dev, seed, warmup, first, n, m_plan_cells.data(), m_plan_pos.data(), s);
        HashGridArgs h;
        h.layout = layout;
        h.positions = m_plan_pos.data();
        h.n_host = n;
        h.capacity = uint32_t(m_plan_pos.size());
        hash_encode(h, grid_params, m_plan_enc.data(), s);
        MlpInferenceArgs a;
        a.weights = mlp_half;
        a.encoded = m_plan_enc.data();
        a.n_host = n;
        a.capacity = uint32_t(m_plan_pos.size());
        a.sigma = m_plan_sigma.data();
        mlp_inference(a, true, s);
        occupancy_splat(m_dev, m_plan_cells.data(), m_plan_sigma.data(), n, min_step, s);
    }
    occupancy_apply(m_dev, cfg.decay, cfg.threshold, s);
}

void DeviceOccupancy::download(OccupancyGrid& host, float threshold, cudaStream_t s) const {
    gpu::cuda_check(cudaStreamSynchronize(s), "occupancy grid update");
    host.set_density(m_density.download(), threshold);
}

}  // namespace npt::nerf::cuda
