#include "bake/bake_grid.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "core/error.h"
#include "core/srgb.h"
#include "nerf/field_batch.h"
#include "nerf/object_frame.h"
#include "nerf/mlp_batch.h"
#include "nerf/sh_encoding.h"

namespace npt::bake {
namespace {

using nerf::CropBox;
using nerf::NerfModel;

// Samples per field_forward call: large enough to amortise the matrix products, small enough that the colour
// MLP's input for 16 directions (chunk * 16 rows) stays a few MB per thread.
constexpr size_t k_chunk = 1024;

std::string vec_text(Vec3 v) { return fmt::format("{:g},{:g},{:g}", v.x, v.y, v.z); }

CropBox model_box(const NerfModel& model) {
    const nerf::MarchParams mp = model.march_params();
    return {mp.aabb_min, mp.aabb_max};
}

// The voxels of one z-slab, by index j * nx + i in increasing order.
struct SlabDensity {
    std::vector<uint32_t> ij;
    std::vector<float> sigma;
};
struct SlabVoxels {
    std::vector<uint32_t> ij;
    std::vector<float> sigma;
    std::vector<Rgb> color;
    std::vector<uint8_t> has_density;
};

// The centres of slab k's voxels that lie in occupied cells, and their index j * nx + i (increasing). An
// isolated model (object_only) keeps only the voxels inside its object box, the cut its renders make.
void slab_candidates(const NerfModel& model, const BakeLayout& L, int k, std::vector<Vec3>& pos,
                     std::vector<uint32_t>& cand) {
    const nerf::OccupancyGridView occ = model.occupancy.view();
    const nerf::ObjectCut cut = model.object && model.object->object_only
                                    ? nerf::object_cut(*model.object, model.world_to_model)
                                    : nerf::ObjectCut{};
    const int nx = L.dims[0], ny = L.dims[1];
    pos.clear();
    cand.clear();
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const Vec3 p = L.model_center(i, j, k);
            if (!occ.is_occupied(p, occ.cascade_of(p)) || cut.outside(p)) continue;
            pos.push_back(p);
            cand.push_back(uint32_t(j) * uint32_t(nx) + uint32_t(i));
        }
}

// Keeps the candidates whose σ passes the threshold.
void keep_dense(const std::vector<uint32_t>& cand, const float* sigma, float threshold, SlabDensity& out) {
    for (size_t t = 0; t < cand.size(); ++t)
        if (sigma[t] >= threshold && std::isfinite(sigma[t])) {
            out.ij.push_back(cand[t]);
            out.sigma.push_back(sigma[t]);
        }
}

// Pass 1 on the CPU: σ at the centres of the slab's voxels that lie in occupied cells; keeps those >= threshold.
void slab_density(const NerfModel& model, const BakeLayout& L, int k, float threshold, nerf::FieldBatch& b,
                  std::vector<Vec3>& pos, std::vector<uint32_t>& cand, SlabDensity& out) {
    const nerf::NerfLayout nl = model.layout();
    slab_candidates(model, L, k, pos, cand);
    std::vector<float> sigma(pos.size());
    for (size_t off = 0; off < pos.size(); off += k_chunk) {
        const size_t m = std::min(k_chunk, pos.size() - off);
        nerf::field_forward(nl, model.params.data(), pos.data() + off, nullptr, m, false, b);
        std::copy_n(b.sigma.begin(), m, sigma.begin() + off);
    }
    keep_dense(cand, sigma.data(), threshold, out);
}

// Where a voxel can be seen from. The colour network is trained only for (point, direction) pairs that a
// camera saw, i.e. where the point was not hidden behind other matter along the direction; from other
// directions its colour is whatever the network extrapolates (measured on lego: a bake averaging over those
// rendered 5-7% darker, docs/benchmarks.md "Bakes that keep the colour"). So each direction's colour is weighted
// by the voxel's transmittance towards the viewer, marched through the baked density, mean-pooled onto a grid
// of at most k_vis_cells per side (visibility needs no fine detail, and the march then costs little).
constexpr int k_vis_cells = 64;
// Transmittance floor: a voxel hidden from every direction (inside the object) gets the plain weighted mean.
constexpr float k_min_visibility = 1e-4f;

struct VisibilityGrid {
    int factor = 1;      // fine voxels per coarse cell along each axis
    int dims[3] = {1, 1, 1};
    Vec3 voxel_model;    // a fine voxel's size in model units along local x, y, z
    std::vector<float> sigma;  // mean σ per coarse cell (per model unit)

    float at(int i, int j, int k) const {
        return sigma[(size_t(k) * size_t(dims[1]) + size_t(j)) * size_t(dims[0]) + size_t(i)];
    }
};

VisibilityGrid make_visibility_grid(const BakeLayout& L, const std::vector<SlabDensity>& dens) {
    VisibilityGrid v;
    const int longest = std::max(L.dims[0], std::max(L.dims[1], L.dims[2]));
    v.factor = std::max(1, (longest + k_vis_cells - 1) / k_vis_cells);
    for (int a = 0; a < 3; ++a) v.dims[a] = (L.dims[a] + v.factor - 1) / v.factor;
    const Vec3 side = nerf::model_to_world_axes(L.crop.max - L.crop.min);
    for (int a = 0; a < 3; ++a) v.voxel_model[a] = side[a] / float(L.dims[a]);
    v.sigma.assign(size_t(v.dims[0]) * size_t(v.dims[1]) * size_t(v.dims[2]), 0.0f);
    const float per_cell = 1.0f / float(v.factor * v.factor * v.factor);
    const uint32_t nx = uint32_t(L.dims[0]);
    for (int k = 0; k < L.dims[2]; ++k)
        for (size_t t = 0; t < dens[size_t(k)].ij.size(); ++t) {
            const uint32_t ij = dens[size_t(k)].ij[t];
            const int i = int(ij % nx) / v.factor, j = int(ij / nx) / v.factor, kc = k / v.factor;
            v.sigma[(size_t(kc) * size_t(v.dims[1]) + size_t(j)) * size_t(v.dims[0]) + size_t(i)] +=
                dens[size_t(k)].sigma[t] * per_cell;
        }
    return v;
}

// Transmittance from fine voxel (i, j, k)'s centre back along -d (d: a ray direction, model axes) to the edge
// of the crop. The march starts one coarse cell and half a fine voxel away, past the voxel's own surface.
float visibility(const VisibilityGrid& v, int i, int j, int k, Vec3 d_model) {
    const Vec3 d = nerf::model_to_world_axes(d_model);  // local axes, as the voxel indices
    const float vmin = std::min(v.voxel_model.x, std::min(v.voxel_model.y, v.voxel_model.z));
    const float vmax = std::max(v.voxel_model.x, std::max(v.voxel_model.y, v.voxel_model.z));
    const float h = 0.5f * float(v.factor) * vmin;  // model units per step
    Vec3 step, p;
    for (int a = 0; a < 3; ++a) step[a] = -d[a] * h / v.voxel_model[a];
    const float t0 = (float(v.factor) + 0.5f) * vmax;
    const int idx[3] = {i, j, k};
    for (int a = 0; a < 3; ++a) p[a] = float(idx[a]) + 0.5f - d[a] * t0 / v.voxel_model[a];
    const float fine[3] = {float(v.dims[0] * v.factor), float(v.dims[1] * v.factor), float(v.dims[2] * v.factor)};
    float tau = 0.0f;
    while (p.x >= 0.0f && p.y >= 0.0f && p.z >= 0.0f && p.x < fine[0] && p.y < fine[1] && p.z < fine[2]) {
        tau += v.at(int(p.x) / v.factor, int(p.y) / v.factor, int(p.z) / v.factor) * h;
        if (tau > 12.0f) break;  // T < 1e-5: hidden
        p += step;
    }
    return std::exp(-tau);
}

// One voxel's colour from its colour for each direction (sigmoid outputs, sRGB-encoded): the weighted mean in
// linear light (what the renderer displays and a camera's pixels average), encoded back to sRGB so that the
// BakedGrid keeps its meaning for every writer.
Rgb combine_colors(const VisibilityGrid& vis, const ColourDirections& cd, int i, int j, int k, const Rgb* per_dir) {
    const size_t n = cd.dirs.size();
    if (n == 1) return per_dir[0];
    Rgb sum(0.0f);
    float wsum = 0.0f;
    for (size_t d = 0; d < n; ++d) {
        const float w = cd.weights[d] * std::max(k_min_visibility, visibility(vis, i, j, k, cd.dirs[d]));
        const Rgb c = per_dir[d];
        sum += Rgb(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z)) * w;
        wsum += w;
    }
    const Rgb m = sum / wsum;
    return Rgb(linear_to_srgb(m.x), linear_to_srgb(m.y), linear_to_srgb(m.z));
}

// Pass 2, which voxels: the slab's density voxels and their 3x3x3 neighbours, without colour yet; pos gets
// their centres.
void slab_color_voxels(const BakeLayout& L, int k, const std::vector<SlabDensity>& dens, SlabVoxels& out,
                       std::vector<Vec3>& pos) {
    const int nx = L.dims[0], ny = L.dims[1], nz = L.dims[2];
    const size_t plane = size_t(nx) * size_t(ny);
    pos.clear();
    // Union of the density voxels of slabs k-1..k+1, then dilated by one voxel along i and j.
    std::vector<uint8_t> mask(plane, 0), tmp(plane, 0);
    bool any = false;
    for (int kk = std::max(0, k - 1); kk <= std::min(nz - 1, k + 1); ++kk)
        for (uint32_t ij : dens[size_t(kk)].ij) {
            mask[ij] = 1;
            any = true;
        }
    if (!any) return;
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const size_t r = size_t(j) * size_t(nx);
            tmp[r + size_t(i)] = mask[r + size_t(i)] | (i > 0 ? mask[r + size_t(i) - 1] : 0) |
                                 (i + 1 < nx ? mask[r + size_t(i) + 1] : 0);
        }
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const size_t c = size_t(j) * size_t(nx) + size_t(i);
            mask[c] = tmp[c] | (j > 0 ? tmp[c - size_t(nx)] : 0) | (j + 1 < ny ? tmp[c + size_t(nx)] : 0);
        }

    // Merge with this slab's density voxels (both in increasing ij).
    const SlabDensity& own = dens[size_t(k)];
    size_t next = 0;
    for (uint32_t ij = 0; ij < plane; ++ij) {
        if (!mask[ij]) continue;
        const bool has = next < own.ij.size() && own.ij[next] == ij;
        out.ij.push_back(ij);
        out.sigma.push_back(has ? own.sigma[next] : 0.0f);
        out.has_density.push_back(has ? 1 : 0);
        if (has) ++next;
        pos.push_back(L.model_center(int(ij % uint32_t(nx)), int(ij / uint32_t(nx)), k));
    }
}

// Pass 2 on the CPU: the slab's voxels with their colour for each direction (the density MLP's outputs once
// per voxel, then the colour MLP once per direction), combined by combine_colors. (BakeColour::albedo takes
// slab_albedo instead.)
void slab_color(const NerfModel& model, const BakeLayout& L, int k, const std::vector<SlabDensity>& dens,
                const std::vector<float>& sh, const ColourDirections& cd, const VisibilityGrid& vis,
                nerf::FieldBatch& b, SlabVoxels& out) {
    const nerf::NerfLayout nl = model.layout();
    const size_t n_dirs = cd.dirs.size();
    std::vector<Vec3> pos;
    slab_color_voxels(L, k, dens, out, pos);
    const int dens_out = nl.density.outputs, col_in = nl.color.inputs, co = nl.color.outputs;
    std::vector<float> in, y;
    std::vector<Rgb> per_dir(n_dirs);
    out.color.resize(pos.size());
    const uint32_t nx = uint32_t(L.dims[0]);
    for (size_t off = 0; off < pos.size(); off += k_chunk) {
        const size_t m = std::min(k_chunk, pos.size() - off);
        nerf::field_forward(nl, model.params.data(), pos.data() + off, nullptr, m, false, b);
        in.resize(m * n_dirs * size_t(col_in));
        y.resize(m * n_dirs * size_t(co));
        for (size_t t = 0; t < m; ++t)
            for (size_t d = 0; d < n_dirs; ++d) {
                float* row = &in[(t * n_dirs + d) * size_t(col_in)];
                std::copy_n(&b.color_in[t * size_t(col_in)], dens_out, row);
                std::copy_n(&sh[d * nerf::k_sh_deg4_dims], nerf::k_sh_deg4_dims, row + dens_out);
            }
        nerf::mlp_forward_batch(nl.color, model.params.data() + nl.color_offset, in.data(), m * n_dirs,
                                y.data(), nullptr);
        for (size_t t = 0; t < m; ++t) {
            for (size_t d = 0; d < n_dirs; ++d) {
                const float* o = &y[(t * n_dirs + d) * size_t(co)];
                per_dir[d] = Rgb(nerf::sigmoidf(o[0]), nerf::sigmoidf(o[1]), nerf::sigmoidf(o[2]));
            }
            const uint32_t ij = out.ij[off + t];
            out.color[off + t] = combine_colors(vis, cd, int(ij % nx), int(ij / nx), k, per_dir.data());
        }
    }
}

// Pass 2 for BakeColour::albedo: the intrinsic field's albedo at the centres of the same voxels as pass 2,
// on the CPU whatever evaluated the density (one small hash grid + MLP per voxel, no directions). The albedo
// is linear; it is stored sRGB-encoded, as BakedGrid::color holds every colour, and the writers decode it.
void slab_albedo(const nerf::IntrinsicFieldView& intrinsic, const BakeLayout& L, int k,
                 const std::vector<SlabDensity>& dens, SlabVoxels& out) {
    std::vector<Vec3> pos;
    slab_color_voxels(L, k, dens, out, pos);
    out.color.resize(pos.size());
    for (size_t t = 0; t < pos.size(); ++t) {
        const Rgb a = intrinsic.query(pos[t]).albedo;
        out.color[t] = Rgb(linear_to_srgb(a.x), linear_to_srgb(a.y), linear_to_srgb(a.z));
    }
}

// The two passes with another evaluator (a GPU): slabs in order, their points gathered into large batches.
constexpr size_t k_field_batch = size_t(1) << 20;

void density_with(BakeField& field, const NerfModel& model, const BakeLayout& L, float threshold,
                  std::vector<SlabDensity>& dens, const std::function<void()>& slab_done) {
    const int nz = L.dims[2];
    std::vector<Vec3> pos, batch;
    std::vector<uint32_t> cand;
    std::vector<std::vector<uint32_t>> pending_cand;
    std::vector<int> pending_k;
    std::vector<float> sigma;
    auto flush = [&] {
        field.density(batch, sigma);
        size_t off = 0;
        for (size_t q = 0; q < pending_k.size(); ++q) {
            keep_dense(pending_cand[q], sigma.data() + off, threshold, dens[size_t(pending_k[q])]);
            off += pending_cand[q].size();
            slab_done();
        }
        batch.clear();
        pending_cand.clear();
        pending_k.clear();
    };
    for (int k = 0; k < nz; ++k) {
        slab_candidates(model, L, k, pos, cand);
        batch.insert(batch.end(), pos.begin(), pos.end());
        pending_cand.push_back(cand);
        pending_k.push_back(k);
        if (batch.size() >= k_field_batch) flush();
    }
    flush();
}

void color_with(BakeField& field, const BakeLayout& L, const std::vector<SlabDensity>& dens,
                const ColourDirections& cd, const VisibilityGrid& vis, std::vector<SlabVoxels>& slabs,
                const std::function<void()>& slab_done) {
    const int nz = L.dims[2];
    const size_t nd = cd.dirs.size();
    const uint32_t nx = uint32_t(L.dims[0]);
    std::vector<Vec3> pos, batch;
    std::vector<int> pending;
    std::vector<Rgb> color;
    auto flush = [&] {
        field.colors(batch, cd.dirs, color);
        size_t off = 0;
        for (int k : pending) {
            SlabVoxels& s = slabs[size_t(k)];
            s.color.resize(s.ij.size());
            tbb::parallel_for(size_t(0), s.ij.size(), [&](size_t t) {
                s.color[t] = combine_colors(vis, cd, int(s.ij[t] % nx), int(s.ij[t] / nx), k,
                                            &color[(off + t) * nd]);
            });
            off += s.ij.size();
            slab_done();
        }
        batch.clear();
        pending.clear();
    };
    for (int k = 0; k < nz; ++k) {
        slab_color_voxels(L, k, dens, slabs[size_t(k)], pos);
        batch.insert(batch.end(), pos.begin(), pos.end());
        pending.push_back(k);
        if (batch.size() * nd >= k_field_batch) flush();
    }
    flush();
}

}  // namespace

Vec3 BakeLayout::local_center(int i, int j, int k) const {
    const int idx[3] = {i, j, k};
    Vec3 p;
    for (int a = 0; a < 3; ++a)
        p[a] = float(double(k_local_min) +
                     (double(idx[a]) + 0.5) * double(k_local_max - k_local_min) / double(dims[a]));
    return p;
}

BakeLayout make_bake_layout(const NerfModel& model, const BakeSettings& settings) {
    const CropBox box = model_box(model);
    BakeLayout L;
    L.crop = settings.crop.value_or(box);
    const CropBox& c = L.crop;
    const std::string crop_text = "--crop " + vec_text(c.min) + "," + vec_text(c.max);
    for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(c.min[a]) || !std::isfinite(c.max[a]))
            throw Error(crop_text + ": every number must be finite");
        if (!(c.min[a] < c.max[a]))
            throw Error(crop_text + ": the minimum must be below the maximum on every axis (" +
                        std::string(1, "xyz"[a]) + ": " + fmt::format("{:g} >= {:g}", c.min[a], c.max[a]) +
                        ")");
        // A little slack for a box typed with rounded numbers.
        const float eps = 1e-5f * (box.max[a] - box.min[a]);
        if (c.min[a] < box.min[a] - eps || c.max[a] > box.max[a] + eps)
            throw Error(crop_text + ": must lie inside the model's box " + vec_text(box.min) + " .. " +
                        vec_text(box.max) + " (model space, 0.5 -+ aabb_scale/2)");
    }
    // Crop side lengths in LOCAL axis order (local x, y, z = model z, x, y).
    const Vec3 side = nerf::model_to_world_axes(c.max - c.min);
    const float longest = std::max(side.x, std::max(side.y, side.z));
    for (int a = 0; a < 3; ++a) {
        double n = 0;
        if (settings.voxel_size > 0.0f) {
            if (!std::isfinite(settings.voxel_size))
                throw Error("--voxel: must be a positive finite number of model units");
            n = std::max(1.0, std::round(double(side[a]) / double(settings.voxel_size)));
            if (n > k_max_bake_resolution)
                throw Error(
                    fmt::format("--voxel {:g}: gives {:.0f} voxels along one side, more than the {} "
                                "a bake supports",
                                settings.voxel_size, n, k_max_bake_resolution));
        } else {
            if (settings.resolution < 1 || settings.resolution > k_max_bake_resolution)
                throw Error(
                    fmt::format("--res {}: must be 1..{}", settings.resolution, k_max_bake_resolution));
            n = side[a] == longest
                    ? double(settings.resolution)
                    : std::max(1.0, std::round(double(settings.resolution) * side[a] / longest));
        }
        L.dims[a] = int(n);
    }
    if (L.voxel_count() > k_max_bake_voxels)
        throw Error(
            fmt::format("{}: the grid would be {}x{}x{} = {} voxels, more than the {} a bake supports",
                        settings.voxel_size > 0.0f ? fmt::format("--voxel {:g}", settings.voxel_size)
                                                   : fmt::format("--res {}", settings.resolution),
                        L.dims[0], L.dims[1], L.dims[2], L.voxel_count(), k_max_bake_voxels));
    L.local_to_model = nerf::local_to_model(Vec3(k_local_min), Vec3(k_local_max), c);
    L.model_per_local = longest / (k_local_max - k_local_min);
    return L;
}

float default_threshold(const NerfModel& model) {
    return model.config.occupancy.threshold / (8.0f * model.march_params().min_step);
}

std::vector<Vec3> average_directions() {
    constexpr int n = 16;
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    std::vector<Vec3> dirs;
    for (int i = 0; i < n; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / n;
        const double r = std::sqrt(1.0 - z * z);
        dirs.emplace_back(float(r * std::cos(golden * i)), float(r * std::sin(golden * i)), float(z));
    }
    return dirs;
}

ColourDirections colour_directions(const NerfModel& model, const BakeSettings& settings) {
    ColourDirections cd;
    if (settings.direction) {
        const Vec3 d = nerf::world_axes_to_model(*settings.direction);
        const float len = length(d);
        if (!(len > 0.0f) || !std::isfinite(len))
            throw Error("--direction " + vec_text(*settings.direction) +
                        ": must be a non-zero finite vector");
        cd.dirs.push_back(d / len);
    } else if (model.view_directions.empty()) {
        cd.dirs = average_directions();
    } else if (model.view_directions.size() <= k_max_colour_directions) {
        cd.dirs = model.view_directions;
    } else {
        // Farthest-point sampling from the first camera: the picks cover the cameras' directions evenly.
        const std::vector<Vec3>& all = model.view_directions;
        std::vector<float> nearest(all.size(), 2.0f);  // 1 - cos of the angle to the nearest pick
        size_t next = 0;
        while (cd.dirs.size() < k_max_colour_directions) {
            cd.dirs.push_back(all[next]);
            size_t far = 0;
            for (size_t c = 0; c < all.size(); ++c) {
                nearest[c] = std::min(nearest[c], 1.0f - dot(all[c], all[next]));
                if (nearest[c] > nearest[far]) far = c;
            }
            next = far;
        }
    }
    cd.weights.assign(cd.dirs.size(), 0.0f);
    if (!settings.direction && cd.dirs.size() < model.view_directions.size()) {
        // Each pick stands for the cameras nearest to it.
        for (const Vec3& c : model.view_directions) {
            size_t best = 0;
            for (size_t d = 1; d < cd.dirs.size(); ++d)
                if (dot(c, cd.dirs[d]) > dot(c, cd.dirs[best])) best = d;
            cd.weights[best] += 1.0f;
        }
    } else {
        std::fill(cd.weights.begin(), cd.weights.end(), 1.0f);
    }
    return cd;
}

void check_colour_settings(const NerfModel& model, const BakeSettings& settings, const std::string& model_name) {
    if (settings.colour != BakeColour::albedo) return;
    if (!model.relightable())
        throw Error(model_name +
                    ": --colour albedo needs a relightable model (trained with --relightable; nerfpt info "
                    "says), this one has no relight section");
    if (settings.direction)
        throw Error("--direction " + vec_text(*settings.direction) +
                    ": the albedo is the same from every direction; use it with --colour radiance");
}

BakedGrid bake_model(const NerfModel& model, const BakeSettings& settings, const BakeProgress& progress,
                     BakeField* field) {
    check_colour_settings(model, settings, "model");
    BakedGrid g;
    g.colour = settings.colour;
    g.layout = make_bake_layout(model, settings);
    const BakeLayout& L = g.layout;
    g.threshold = settings.threshold.value_or(default_threshold(model));
    if (!(g.threshold >= 0.0f) || !std::isfinite(g.threshold))
        throw Error(fmt::format("--threshold {:g}: must be a finite σ >= 0 (per model unit)", g.threshold));

    const ColourDirections cd = colour_directions(model, settings);
    std::vector<float> sh(cd.dirs.size() * nerf::k_sh_deg4_dims);
    for (size_t d = 0; d < cd.dirs.size(); ++d) nerf::sh_encode_deg4(cd.dirs[d], &sh[d * nerf::k_sh_deg4_dims]);

    const int nz = L.dims[2];
    const uint64_t plane = uint64_t(L.dims[0]) * uint64_t(L.dims[1]);
    const uint64_t total = 2 * uint64_t(nz) * plane;
    std::atomic<uint64_t> done{0};
    auto report = [&] {
        const uint64_t now = done.fetch_add(plane) + plane;
        if (progress) progress(now, total);
    };

    std::vector<SlabDensity> dens(static_cast<size_t>(nz));
    std::vector<SlabVoxels> slabs(static_cast<size_t>(nz));
    // On the CPU, slabs are independent and each writes only its own output, so the result is the same for any
    // thread count and scheduling.
    if (field) {
        density_with(*field, model, L, g.threshold, dens, report);
    } else {
        tbb::parallel_for(tbb::blocked_range<int>(0, nz, 1), [&](const tbb::blocked_range<int>& r) {
            nerf::FieldBatch b;
            std::vector<Vec3> pos;
            std::vector<uint32_t> cand;
            for (int k = r.begin(); k != r.end(); ++k) {
                slab_density(model, L, k, g.threshold, b, pos, cand, dens[size_t(k)]);
                report();
            }
        });
    }
    if (settings.colour == BakeColour::albedo) {
        const nerf::IntrinsicFieldView intrinsic = model.intrinsic();
        tbb::parallel_for(tbb::blocked_range<int>(0, nz, 1), [&](const tbb::blocked_range<int>& r) {
            for (int k = r.begin(); k != r.end(); ++k) {
                slab_albedo(intrinsic, L, k, dens, slabs[size_t(k)]);
                report();
            }
        });
    } else if (field) {
        const VisibilityGrid vis = make_visibility_grid(L, dens);
        color_with(*field, L, dens, cd, vis, slabs, report);
    } else {
        const VisibilityGrid vis = make_visibility_grid(L, dens);
        tbb::parallel_for(tbb::blocked_range<int>(0, nz, 1), [&](const tbb::blocked_range<int>& r) {
            nerf::FieldBatch b;
            for (int k = r.begin(); k != r.end(); ++k) {
                slab_color(model, L, k, dens, sh, cd, vis, b, slabs[size_t(k)]);
                report();
            }
        });
    }

    size_t n = 0;
    for (const auto& s : slabs) n += s.ij.size();
    g.coords.reserve(3 * n);
    g.sigma.reserve(n);
    g.color.reserve(n);
    g.has_density.reserve(n);
    for (int k = 0; k < nz; ++k) {
        SlabVoxels& s = slabs[size_t(k)];
        for (size_t t = 0; t < s.ij.size(); ++t) {
            g.coords.push_back(int32_t(s.ij[t] % uint32_t(L.dims[0])));
            g.coords.push_back(int32_t(s.ij[t] / uint32_t(L.dims[0])));
            g.coords.push_back(k);
            g.density_voxels += s.has_density[t];
        }
        g.sigma.insert(g.sigma.end(), s.sigma.begin(), s.sigma.end());
        g.color.insert(g.color.end(), s.color.begin(), s.color.end());
        g.has_density.insert(g.has_density.end(), s.has_density.begin(), s.has_density.end());
        s = SlabVoxels();  // free as we go: the slabs and the result together would double the peak
    }
    return g;
}

}  // namespace npt::bake
