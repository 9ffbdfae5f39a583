#include "nerf/field_batch.h"

#include <tbb/parallel_for.h>

#include "nerf/sh_encoding.h"

namespace npt::nerf {

void field_forward(const NerfLayout& layout, const float* params, const Vec3* positions, const Vec3* dirs,
                   size_t n, bool with_color, FieldBatch& b) {
    const int enc_dims = layout.grid.output_dims();
    const int dens_out = layout.density.outputs;
    const int col_in = layout.color.inputs;
    b.n = n;
    b.encoded.resize(n * enc_dims);
    b.color_in.resize(n * col_in);
    b.sigma.resize(n);
    const float* grid = params + layout.grid_offset;
    const HashLevels levels = hash_levels(layout.grid);
    for (size_t i = 0; i < n; ++i)
        hash_encode(layout.grid, levels, grid, layout.grid_position(positions[i]), &b.encoded[i * enc_dims]);

    // The density MLP writes its output straight into the first columns of the colour MLP's input.
    b.density_out.resize(n * dens_out);
    mlp_forward_batch(layout.density, params + layout.density_offset, b.encoded.data(), n,
                      b.density_out.data(), &b.density_acts);
    const float* dens_y = b.density_out.data();
    for (size_t i = 0; i < n; ++i) {
        float* ci = &b.color_in[i * col_in];
        for (int k = 0; k < dens_out; ++k) ci[k] = dens_y[i * dens_out + k];
        b.sigma[i] = density_activation(ci[0]);
    }
    if (!with_color) return;
    for (size_t i = 0; i < n; ++i) sh_encode_deg4(dirs[i], &b.color_in[i * col_in + dens_out]);
    b.rgb.resize(n);
    b.color_out.resize(n * layout.color.outputs);
    mlp_forward_batch(layout.color, params + layout.color_offset, b.color_in.data(), n, b.color_out.data(),
                      &b.color_acts);
    const float* y = b.color_out.data();
    const int co = layout.color.outputs;
    for (size_t i = 0; i < n; ++i)
        b.rgb[i] = Rgb(sigmoidf(y[i * co]), sigmoidf(y[i * co + 1]), sigmoidf(y[i * co + 2]));
}

void field_backward(const NerfLayout& layout, const float* params, const float* d_sigma, const Rgb* d_rgb,
                    FieldBatch& b, float* d_params) {
    const size_t n = b.n;
    const int co = layout.color.outputs;
    const int col_in = layout.color.inputs;
    const int dens_out = layout.density.outputs;
    // Colour MLP: through the sigmoid, then the network, down to its input.
    std::vector<float> d_col_out(n * co);
    for (size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const float s = b.rgb[i][k];
            d_col_out[i * co + k] = d_rgb[i][k] * s * (1.0f - s);
        }
    b.d_color_in.resize(n * col_in);
    mlp_backward_batch(layout.color, params + layout.color_offset, b.color_in.data(), b.color_acts,
                       d_col_out.data(), d_params + layout.color_offset, b.d_color_in.data());
    // Density MLP: its outputs feed the colour MLP, and output 0 is also log-density.
    const float* dens_y = b.density_out.data();
    b.d_density_out.resize(n * dens_out);
    for (size_t i = 0; i < n; ++i) {
        float* dd = &b.d_density_out[i * dens_out];
        for (int k = 0; k < dens_out; ++k) dd[k] = b.d_color_in[i * col_in + k];
        dd[0] += d_sigma[i] * density_activation_grad(dens_y[i * dens_out]);
    }
    b.d_encoded.resize(n * layout.grid.output_dims());
    mlp_backward_batch(layout.density, params + layout.density_offset, b.encoded.data(), b.density_acts,
                       b.d_density_out.data(), d_params + layout.density_offset, b.d_encoded.data());
}

void accumulate_grid_gradient(const NerfLayout& layout, const std::vector<const Vec3*>& positions,
                              const std::vector<const FieldBatch*>& chunks, float* d_params,
                              uint8_t* reached) {
    const HashGridConfig& cfg = layout.grid;
    const int nf = cfg.features_per_level, enc_dims = cfg.output_dims();
    float* d_grid = d_params + layout.grid_offset;
    const HashLevels levels = hash_levels(cfg);
    tbb::parallel_for(0, cfg.levels, [&](int level) {
        const HashLevel lv = levels.level[level];
        for (size_t c = 0; c < chunks.size(); ++c) {
            const FieldBatch& b = *chunks[c];
            for (size_t i = 0; i < b.n; ++i) {
                const float* d_out = &b.d_encoded[i * enc_dims + level * nf];
                // A sample past its ray's stop has no gradient (a third of a step's samples): adding its
                // zeros would change no sum, only cost the lookups (and mark entries as reached).
                bool zero = true;
                for (int f = 0; f < nf; ++f) zero = zero && d_out[f] == 0.0f;
                if (zero) continue;
                HashCorner corners[8];
                hash_level_corners(cfg, lv, level, layout.grid_position(positions[c][i]), corners);
                for (int k = 0; k < 8; ++k) {
                    float* g = d_grid + size_t(corners[k].index) * nf;
                    for (int f = 0; f < nf; ++f) g[f] += corners[k].weight * d_out[f];
                }
                // Levels own disjoint entry ranges, so the parallel levels never write one flag.
                if (reached)
                    for (int k = 0; k < 8; ++k) reached[corners[k].index] = 1;
            }
        }
    });
}

}  // namespace npt::nerf
