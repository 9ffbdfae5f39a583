#include "nerf/nerf_model.h"

#include <cmath>

#include "core/error.h"
#include "core/memory.h"
#include "core/rng.h"
#include "nerf/mlp_batch.h"

namespace npt::nerf {

NerfLayout make_layout(const NerfConfig& config, float aabb_scale) {
    NerfLayout l;
    l.grid = config.encoding.grid;
    l.grid.per_level_scale = per_level_scale_for(
        l.grid.base_resolution, config.encoding.finest_resolution * aabb_scale, l.grid.levels);
    l.density = {l.grid.output_dims(), config.density_mlp.width, config.density_mlp.hidden_layers,
                 config.density_mlp.outputs};
    l.color = {config.density_mlp.outputs + k_sh_deg4_dims, config.color_mlp.width,
               config.color_mlp.hidden_layers, config.color_mlp.outputs};
    l.density_offset = 0;
    l.color_offset = l.density_offset + l.density.param_count();
    l.grid_offset = l.color_offset + l.color.param_count();
    l.total = l.grid_offset + l.grid.param_count();
    l.aabb_min = Vec3(0.5f - 0.5f * aabb_scale);
    l.inv_aabb_scale = 1.0f / aabb_scale;
    return l;
}

IntrinsicLayout make_intrinsic_layout(const IntrinsicConfig& config, float aabb_scale) {
    IntrinsicLayout l;
    l.grid = config.grid;
    l.grid.per_level_scale =
        per_level_scale_for(l.grid.base_resolution, config.finest_resolution * aabb_scale, l.grid.levels);
    l.mlp = {l.grid.output_dims(), config.width, config.hidden_layers, k_intrinsic_outputs};
    l.mlp_offset = 0;
    l.grid_offset = l.mlp.param_count();
    l.total = l.grid_offset + l.grid.param_count();
    l.aabb_min = Vec3(0.5f - 0.5f * aabb_scale);
    l.inv_aabb_scale = 1.0f / aabb_scale;
    l.diffuse = config.diffuse;
    return l;
}

MarchParams NerfModel::march_params() const {
    MarchParams mp;
    const float half = 0.5f * aabb_scale;
    mp.aabb_min = Vec3(0.5f - half);
    mp.aabb_max = Vec3(0.5f + half);
    constexpr float k_sqrt3 = 1.7320508075688772f;
    mp.min_step = k_sqrt3 / float(config.march.max_steps);
    mp.max_step = k_sqrt3 * float(1 << (occupancy.cascades() - 1)) / float(occupancy.resolution());
    mp.cone_angle = config.march.cone_angle >= 0.0f ? config.march.cone_angle
                                                    : (aabb_scale > 1.0f ? 1.0f / 256.0f : 0.0f);
    mp.max_samples = config.march.max_samples_per_ray;
    return mp;
}

Mat4 ngp_world_to_model(float scale, Vec3 offset) {
    // instant-ngp: p' = p * scale + offset, then rows cycled so that model (x, y, z) = world (y, z, x).
    Mat4 m;
    m.m = {{{0, scale, 0, offset.y}, {0, 0, scale, offset.z}, {scale, 0, 0, offset.x}, {0, 0, 0, 1}}};
    return m;
}

std::vector<Vec3> training_view_directions(const std::vector<Camera>& cameras, const Mat4& world_to_model) {
    std::vector<Vec3> dirs;
    dirs.reserve(cameras.size());
    for (const Camera& c : cameras) {
        const Mat4& m = c.camera_to_world;
        const Vec3 forward(-float(m.m[0][2]), -float(m.m[1][2]), -float(m.m[2][2]));
        const Vec3 d = world_to_model.transform_vector(forward);
        const float len = length(d);
        if (len > 0.0f && std::isfinite(len)) dirs.push_back(d / len);
    }
    return dirs;
}

NerfModel create_model(const NerfConfig& config, float aabb_scale, const Mat4& world_to_model) {
    if (!(aabb_scale > 0.0f) || !std::isfinite(aabb_scale))
        throw Error("aabb_scale must be a positive number, not " + std::to_string(aabb_scale));
    NerfModel m;
    m.config = config;
    m.aabb_scale = aabb_scale;
    m.world_to_model = world_to_model;
    const NerfLayout l = m.layout();
    with_memory_context(
        "the model's " + std::to_string(l.total) + " parameters", double(l.total) * 4.0,
        "lower encoding.log2_table_size, encoding.levels or encoding.features_per_level in the config",
        [&] { m.params.resize(l.total); });
    Pcg32 rng(config.training.seed, 0x5eed);
    init_mlp_xavier(l.density, m.params.data() + l.density_offset, rng);
    init_mlp_xavier(l.color, m.params.data() + l.color_offset, rng);
    for (size_t i = l.grid_offset; i < l.total; ++i) m.params[i] = (2.0f * rng.next_float() - 1.0f) * 1e-4f;
    m.occupancy = OccupancyGrid(cascades_for_aabb_scale(aabb_scale), config.occupancy.resolution);
    return m;
}

}  // namespace npt::nerf
