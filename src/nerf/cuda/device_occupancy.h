// The occupancy grid resident on the GPU: its buffers, the upload from and download to the host grid, and the
// update step of training (plan -> density of the points -> splat -> decay and threshold).
#pragma once

#include <cuda_fp16.h>
#include <cuda_runtime.h>

#include <cstdint>

#include "core/cuda/device_buffer.h"
#include "nerf/cuda/occupancy_kernels.h"
#include "nerf/nerf_config.h"
#include "nerf/nerf_field.h"
#include "nerf/occupancy_grid.h"

namespace npt::nerf::cuda {

class DeviceOccupancy {
  public:
    // Copies the host grid's densities; occupied flags and the occupied-cell list are derived on the device
    // with `threshold` (as OccupancyGrid::set_density does).
    DeviceOccupancy(const OccupancyGrid& host, float threshold, cudaStream_t s);

    // The bit-field form (see OccupancyGridView::occupied_bits).
    OccupancyGridView view() const {
        return {nullptr, m_dev.cascades, m_dev.resolution, m_bits.data(), m_coarse.size() ? m_coarse.data() : nullptr};
    }
    uint32_t cells() const { return m_dev.cells; }
    // The box around the occupied cells, as float keys (OccupancyDevice::occupied_box).
    const uint32_t* occupied_box() const { return m_box.data(); }

    // One update with the current network: `grid_params` (fp32 hash table) and `mlp_half` (fp16 weights).
    void update(const OccupancyConfig& cfg, const NerfLayout& layout, const float* grid_params,
                const __half* mlp_half, bool warmup, uint64_t seed, float min_step, cudaStream_t s);

    // Densities back into the host grid (which recomputes its flags with `threshold`).
    void download(OccupancyGrid& host, float threshold, cudaStream_t s) const;

  private:
    OccupancyDevice m_dev;
    gpu::DeviceBuffer<float> m_density, m_estimate;
    gpu::DeviceBuffer<uint8_t> m_occupied;
    gpu::DeviceBuffer<uint32_t> m_bits, m_coarse, m_box;
    gpu::DeviceBuffer<uint32_t> m_list, m_count;
    gpu::DeviceBuffer<double> m_sum;
    // Points of one chunk of an update.
    uint32_t m_chunk = 0;
    gpu::DeviceBuffer<uint32_t> m_plan_cells;
    gpu::DeviceBuffer<Vec3> m_plan_pos;
    gpu::DeviceBuffer<__half> m_plan_enc;
    gpu::DeviceBuffer<float> m_plan_sigma;
};

}  // namespace npt::nerf::cuda
