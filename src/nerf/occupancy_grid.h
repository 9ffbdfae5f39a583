// The occupancy grid that lets training and rendering skip empty space (instant-ngp's density grid): per cell
// the largest recent density estimate, decayed at every update, and an occupied flag derived from it.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/rng.h"
#include "nerf/nerf_config.h"
#include "nerf/occupancy_view.h"

namespace npt::nerf {

// The grid stores sigma x min_step (OccupancyGrid::apply_update). Across one cell of a cascade whose cells are
// cascade_size / resolution model units wide, that is an opacity of 1 - exp(-density x cascade_size /
// (resolution x min_step)); the second function is its inverse.
inline double occupancy_cell_opacity(double density, double cascade_size, int resolution, double min_step) {
    return 1.0 - std::exp(-density * cascade_size / (double(resolution) * min_step));
}
inline double occupancy_density_for_opacity(double opacity, double cascade_size, int resolution, double min_step) {
    return -std::log(1.0 - opacity) * double(resolution) * min_step / cascade_size;
}

// Number of cascades needed to cover instant-ngp's aabb of side aabb_scale: 1 + ceil(log2(aabb_scale)).
int cascades_for_aabb_scale(float aabb_scale);

class OccupancyGrid {
public:
    OccupancyGrid() = default;
    // Every cell starts occupied (density +inf is not used: cells start at a large value that decays).
    OccupancyGrid(int cascades, int resolution);

    int cascades() const { return m_cascades; }
    int resolution() const { return m_resolution; }
    size_t cell_count() const { return m_density.size(); }
    OccupancyGridView view() const { return {m_occupied.data(), m_cascades, m_resolution}; }

    // Cells to re-estimate at update number `update_index`: while update_index * interval < warmup_steps,
    // every cascades-th cell starting at update_index mod cascades (all cells over that many updates; all of
    // them each time for one cascade); later a random quarter, plus as many random occupied cells (as
    // instant-ngp). For each, a uniformly random position inside the cell, in model space.
    void plan_update(const OccupancyConfig& cfg, int update_index, Pcg32& rng, std::vector<uint32_t>& cells,
                     std::vector<Vec3>& positions) const;
    // density[cell] = max(density[cell] * decay, sigma * min_step) for planned cells, decay only for the
    // others; then occupied = density > min(threshold, mean density). sigma[i] belongs to cells[i].
    void apply_update(const OccupancyConfig& cfg, const std::vector<uint32_t>& cells,
                      const std::vector<float>& sigma, float min_step);

    float mean_density() const { return m_mean; }
    double occupied_fraction() const;

    // Raw access for the model file.
    const std::vector<float>& density() const { return m_density; }
    // Restores a stored grid and recomputes occupied flags with `threshold`. Throws npt::Error when the size
    // does not match cascades * resolution^3 or a value is not finite.
    void set_density(std::vector<float> density, float threshold);

private:
    void refresh_occupied(float threshold);

    int m_cascades = 0;
    int m_resolution = 0;
    std::vector<float> m_density;    // optical thickness of a minimum step, per cell
    std::vector<uint8_t> m_occupied; // density > min(threshold, mean)
    float m_mean = 0;
};

}  // namespace npt::nerf
