// Occupancy grid updates (instant-ngp's density grid): which cells to re-estimate, the decayed-max update and
// the occupied flags derived from it.
#include "nerf/occupancy_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/error.h"

namespace npt::nerf {

namespace {

// instant-ngp supports aabb_scale up to 128, i.e. 8 cascades; cascade_size() shifts an int by the cascade.
constexpr int k_max_cascades = 8;
// Cells per axis, and cells in all, are bounded so that an index fits uint32_t and a grid stays allocatable
// (2^28 cells are 1.25 GB; instant-ngp's default is 8 * 128^3 = 2^24).
constexpr int k_max_resolution = 1024;
constexpr size_t k_max_cells = size_t(1) << 28;
// A fresh cell has no estimate (0) but counts as occupied until the first update, which (during warm-up)
// estimates every cell. Starting from a large value instead would keep empty space occupied for ~90 updates
// (0.95^90 = 0.01), i.e. ~1400 steps in which nothing is skipped: most of a CPU run's time budget.
constexpr float k_initial_density = 0.0f;

// Uniform integer in [0, n) from 32 random bits without the bias of a modulo (Lemire's multiply-shift; the
// remaining bias is below n / 2^32, negligible for grids of up to 2^31 cells).
uint32_t uniform_index(Pcg32& rng, uint32_t n) { return uint32_t((uint64_t(rng.next_u32()) * n) >> 32); }

}  // namespace

int cascades_for_aabb_scale(float aabb_scale) {
    if (!std::isfinite(aabb_scale) || aabb_scale <= 0.0f)
        throw Error("aabb_scale must be a positive number (got " + std::to_string(aabb_scale) + ")");
    if (aabb_scale <= 1.0f) return 1;
    const int cascades = 1 + int(std::ceil(std::log2(double(aabb_scale))));
    if (cascades > k_max_cascades)
        throw Error("aabb_scale " + std::to_string(aabb_scale) + " is too large: at most 128 is supported");
    return cascades;
}

OccupancyGrid::OccupancyGrid(int cascades, int resolution) : m_cascades(cascades), m_resolution(resolution) {
    if (cascades < 1 || cascades > k_max_cascades)
        throw Error("occupancy grid: cascades must be in [1, 8] (got " + std::to_string(cascades) + ")");
    if (resolution < 2 || resolution > k_max_resolution || resolution % 2 != 0)
        throw Error("occupancy grid: 'resolution' must be even and in [2, 1024] (got " +
                    std::to_string(resolution) + ")");
    const size_t r = size_t(resolution);
    if (size_t(cascades) * r * r * r > k_max_cells)
        throw Error("occupancy grid: " + std::to_string(cascades) + " cascades of " +
                    std::to_string(resolution) + "^3 cells are too many (at most 2^28 in all)");
    m_density.assign(size_t(cascades) * r * r * r, k_initial_density);
    m_occupied.assign(m_density.size(), 1);
    m_mean = k_initial_density;
}

void OccupancyGrid::plan_update(const OccupancyConfig& cfg, int update_index, Pcg32& rng,
                                std::vector<uint32_t>& cells, std::vector<Vec3>& positions) const {
    cells.clear();
    positions.clear();
    const uint32_t n = uint32_t(m_density.size());
    if (n == 0) return;
    if (int64_t(update_index) * cfg.update_interval < cfg.warmup_steps) {
        // One cascade's worth of cells per update, in turn (every `cascades`-th cell from update_index mod
        // cascades), so that each cell is estimated once every `cascades` updates. instant-ngp estimates all
        // of them every time: cheap on a GPU, but on a CPU with five cascades (aabb_scale 16) it took 43 of
        // the first 76 s of training. With one cascade (NeRF-synthetic) this is instant-ngp's rule. Cells not
        // yet estimated keep their large initial density, so they stay occupied until their turn.
        const uint32_t rounds = uint32_t(m_cascades);
        const uint32_t phase = uint32_t(update_index) % rounds;
        cells.reserve(n / rounds + 1);
        for (uint32_t i = phase; i < n; i += rounds) cells.push_back(i);
    } else {
        const uint32_t quarter = std::max<uint32_t>(1, n / 4);
        cells.reserve(2 * size_t(quarter));
        for (uint32_t i = 0; i < quarter; ++i) cells.push_back(uniform_index(rng, n));
        // Occupied cells are where the field changes during training; an empty grid has none to add.
        std::vector<uint32_t> occupied;
        for (uint32_t i = 0; i < n; ++i)
            if (m_occupied[i]) occupied.push_back(i);
        if (!occupied.empty())
            for (uint32_t i = 0; i < quarter; ++i)
                cells.push_back(occupied[uniform_index(rng, uint32_t(occupied.size()))]);
    }

    const OccupancyGridView v = view();
    const uint32_t r = uint32_t(m_resolution);
    const uint32_t per_cascade = r * r * r;
    positions.resize(cells.size());
    for (size_t k = 0; k < cells.size(); ++k) {
        const uint32_t cell = cells[k];
        const int c = int(cell / per_cascade);
        const uint32_t local = cell % per_cascade;
        const float xyz[3] = {float(local % r), float((local / r) % r), float(local / (r * r))};
        const float size = v.cascade_size(c);
        Vec3 p;
        for (int a = 0; a < 3; ++a) p[a] = 0.5f + ((xyz[a] + rng.next_float()) / float(r) - 0.5f) * size;
        // x + u can round up to x + 1 for large x; the cell centre keeps the position inside its cell.
        if (v.cell_index(p, c) != int64_t(cell))
            for (int a = 0; a < 3; ++a) p[a] = 0.5f + ((xyz[a] + 0.5f) / float(r) - 0.5f) * size;
        positions[k] = p;
    }
}

void OccupancyGrid::apply_update(const OccupancyConfig& cfg, const std::vector<uint32_t>& cells,
                                 const std::vector<float>& sigma, float min_step) {
    if (cells.size() != sigma.size())
        throw std::invalid_argument("OccupancyGrid::apply_update: " + std::to_string(cells.size()) +
                                    " cells but " + std::to_string(sigma.size()) + " densities");
    // A cell planned twice takes the larger estimate and decays once (instant-ngp splats the estimates with
    // an atomic max into a scratch grid, then applies max(density * decay, estimate) to every cell). 0 is
    // "no estimate": densities are never negative, so max with 0 leaves the decayed value.
    std::vector<float> estimate(m_density.size(), 0.0f);
    for (size_t k = 0; k < cells.size(); ++k) {
        if (cells[k] >= m_density.size())
            throw std::invalid_argument("OccupancyGrid::apply_update: cell " + std::to_string(cells[k]) +
                                        " out of range");
        // fmaxf drops a NaN from the network instead of letting it poison the cell for good.
        estimate[cells[k]] = std::fmax(estimate[cells[k]], sigma[k] * min_step);
    }
    for (size_t i = 0; i < m_density.size(); ++i)
        m_density[i] = std::fmax(m_density[i] * cfg.decay, estimate[i]);
    refresh_occupied(cfg.threshold);
}

double OccupancyGrid::occupied_fraction() const {
    if (m_occupied.empty()) return 0.0;
    size_t count = 0;
    for (uint8_t o : m_occupied) count += o;
    return double(count) / double(m_occupied.size());
}

void OccupancyGrid::set_density(std::vector<float> density, float threshold) {
    if (density.size() != m_density.size())
        throw Error("occupancy grid 'density': " + std::to_string(density.size()) + " values, expected " +
                    std::to_string(m_density.size()) + " (" + std::to_string(m_cascades) + " cascades of " +
                    std::to_string(m_resolution) + "^3)");
    for (size_t i = 0; i < density.size(); ++i)
        if (!std::isfinite(density[i]))
            throw Error("occupancy grid 'density': value " + std::to_string(i) + " is not finite (" +
                        std::to_string(density[i]) + ")");
    m_density = std::move(density);
    refresh_occupied(threshold);
}

void OccupancyGrid::refresh_occupied(float threshold) {
    // The mean is over every cell of every cascade (the grid's mean, as OccupancyConfig says); instant-ngp
    // averages the innermost cascade only.
    double sum = 0.0;
    for (float d : m_density) sum += d;
    m_mean = m_density.empty() ? 0.0f : float(sum / double(m_density.size()));
    // No cell has an estimate yet (a fresh grid, or one saved before its first update): nothing is known to
    // be empty, so nothing is skipped.
    if (m_mean == 0.0f) {
        std::fill(m_occupied.begin(), m_occupied.end(), uint8_t(1));
        return;
    }
    const float cut = std::min(threshold, m_mean);
    for (size_t i = 0; i < m_density.size(); ++i) m_occupied[i] = m_density[i] > cut ? 1 : 0;
}

}  // namespace npt::nerf
