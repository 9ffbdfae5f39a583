// A volume's field as the per-sample code sees it: a dense grid of density and colour, its map from the
// volume cube's local space to continuous voxel-index space, and trilinear lookup (zero outside the grid).
// Conventions (docs/formats.md, "Volumes"): the value of voxel (i, j, k) sits at index-space point (i, j, k)
// (OpenVDB's convention); a local point p has index coordinates x = local_to_index * p, and the field there
// is the trilinear interpolation of the 8 voxels around x, voxels outside [0, n) counting as 0.
#pragma once

#include "core/platform.h"
#include "core/vec.h"

namespace npt::media {

// Affine map: x = m * p + t (row-major 3x3).
struct Affine3 {
    float m[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    Vec3 t;
    NPT_HD Vec3 apply(Vec3 p) const {
        return {m[0] * p.x + m[1] * p.y + m[2] * p.z + t.x, m[3] * p.x + m[4] * p.y + m[5] * p.z + t.y,
                m[6] * p.x + m[7] * p.y + m[8] * p.z + t.z};
    }
    NPT_HD Vec3 apply_vector(Vec3 v) const {
        return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
                m[6] * v.x + m[7] * v.y + m[8] * v.z};
    }
};

struct GridView {
    int nx = 0, ny = 0, nz = 0;
    const float* density = nullptr;  // nx * ny * nz, x fastest, then y, then z; >= 0 and finite
    const Vec3* color = nullptr;     // same layout; linear RGB
    Affine3 local_to_index;
    // Device copies only (render/gpu/device_scene.h): a CUDA texture object of float4 (density, colour) with
    // hardware trilinear filtering and a zero border, the same field from one fetch instead of eight voxel
    // reads (weights in 8-bit fixed point: within 1/256 of a voxel-to-voxel difference). 0: none.
    unsigned long long texture = 0;

    NPT_HD NPT_INLINE bool valid() const { return nx > 0 && ny > 0 && nz > 0 && density && color; }
    NPT_HD NPT_INLINE size_t index(int i, int j, int k) const {
        return (size_t(k) * size_t(ny) + size_t(j)) * size_t(nx) + size_t(i);
    }
    NPT_HD NPT_INLINE bool inside(int i, int j, int k) const {
        return i >= 0 && j >= 0 && k >= 0 && i < nx && j < ny && k < nz;
    }
};

// Density and colour at continuous index coordinates x (already mapped from local space). The colour returned
// is the trilinear interpolation of colour itself (not of density x colour), as Cycles and OpenVDB samplers
// do.
struct FieldSample {
    float density;
    Vec3 color;
};

NPT_HD NPT_INLINE FieldSample sample_trilinear(const GridView& g, Vec3 x) {
    FieldSample s{0.0f, Vec3(0.0f)};
    float fx = floorf(x.x), fy = floorf(x.y), fz = floorf(x.z);
    // Reject in float before converting: int() of NaN or of a huge value is undefined. The 8 neighbours are
    // all outside the grid when floor(x) < -1 or >= n on any axis (this also rejects NaN).
    if (!(fx >= -1.0f && fy >= -1.0f && fz >= -1.0f && fx < float(g.nx) && fy < float(g.ny) &&
          fz < float(g.nz)))
        return s;
#if defined(__CUDA_ARCH__)
    if (g.texture) {  // texel (i, j, k) is centred at i + 0.5 in unnormalised coordinates
        const float4 v = tex3D<float4>(cudaTextureObject_t(g.texture), x.x + 0.5f, x.y + 0.5f, x.z + 0.5f);
        return {v.x, Vec3(v.y, v.z, v.w)};
    }
#endif
    int i0 = int(fx), j0 = int(fy), k0 = int(fz);
    float tx = x.x - fx, ty = x.y - fy, tz = x.z - fz;
    for (int c = 0; c < 8; ++c) {
        int di = c & 1, dj = (c >> 1) & 1, dk = (c >> 2) & 1;
        int i = i0 + di, j = j0 + dj, k = k0 + dk;
        if (!g.inside(i, j, k)) continue;
        float w = (di ? tx : 1.0f - tx) * (dj ? ty : 1.0f - ty) * (dk ? tz : 1.0f - tz);
        size_t idx = g.index(i, j, k);
        s.density += w * g.density[idx];
        s.color += g.color[idx] * w;
    }
    return s;
}

}  // namespace npt::media
