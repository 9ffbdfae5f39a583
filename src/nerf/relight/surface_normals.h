// Normals of a trained NeRF's surface, for the relight stage's shading and for the normal field it fits. Two
// estimators, measured against the dev set's ground truth (docs/benchmarks.md, issue 24):
//  - the density normal: -grad(log sigma) by central differences at a point. Cheap, but a NeRF's density is noisy
//    at the scale of its finest grid cells, so it scatters by tens of degrees;
//  - the depth-stencil normal: four camera rays a few pixels around the pixel, each ending at its expected
//    termination point (the volume weights' mean distance), crossed. It averages over the whole surface layer
//    the rays cross and over the stencil's footprint, so it is smooth; where the stencil straddles an edge it is
//    unreliable and is reported as missing.
#pragma once

#include <cstdint>
#include <vector>

#include "core/vec.h"
#include "nerf/dataset.h"
#include "nerf/nerf_model.h"
#include "nerf/relight/field_query.h"

namespace npt::nerf {

// A training pixel and the lattice offset its rays march with.
struct PixelRef {
    uint32_t camera = 0;
    float px = 0.0f, py = 0.0f;  // pixel coordinates (x right, y down), continuous
    float jitter = 0.5f;
};

// Unit model-space normals at `points`, turned toward `toward` (unit, per point); zero where the gradient
// vanishes or is not finite. `step`: the central-difference step in model units.
std::vector<Vec3> density_normals(FieldQuery& query, const std::vector<Vec3>& points,
                                  const std::vector<Vec3>& toward, float step);

// Unit model-space normals of the surface seen through each pixel, turned toward its camera; zero where the
// stencil's rays are not mostly opaque (alpha < 0.5) or straddle a depth edge. `half_width`: pixels from the
// centre to each of the four stencil rays, which share the pixel's jitter (so their noise is correlated and
// cancels in the differences).
std::vector<Vec3> depth_stencil_normals(const NerfModel& model, FieldQuery& query,
                                        const std::vector<Camera>& cameras, const std::vector<PixelRef>& pixels,
                                        float half_width);

// Each normal replaced by the normalised weighted mean of the normals of the points within `radius` of its point
// (model units): weights fall off as a Gaussian of the distance (sigma = radius / 2) and with the normals'
// agreement, max(0, n_i . n_j)^4, so that the two sides of a thin part or the faces of an edge do not blend.
// What it removes: a NeRF's small bumps (it carves texture edges into its density, and noise). What it keeps:
// shape larger than the radius. Zero normals stay zero and are ignored; radius <= 0 returns the input.
std::vector<Vec3> smooth_normals(const std::vector<Vec3>& points, const std::vector<Vec3>& normals, float radius);

}  // namespace npt::nerf
