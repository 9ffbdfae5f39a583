// Training rays where the subject is: each training image's rectangle around the projection of a box that
// holds the subject (for `nerfpt capture`, the object stage's box), so that a share of each step's rays lands
// on the object instead of the room around it (train_pixel.h draws them).
#pragma once

#include <array>
#include <vector>

#include "core/vec.h"
#include "nerf/dataset.h"
#include "nerf/train_pixel.h"

namespace npt::nerf {

// The rectangle of each camera that holds the eight world-space corners' projections, widened by margin_px on
// every side and clipped to the image. A camera that has a corner behind it (or too close to its plane) gets
// its whole image: the projection is no bound there.
std::vector<PixelRect> subject_rects(const std::vector<Camera>& cameras, const std::array<Vec3, 8>& corners,
                                     float margin_px);

}  // namespace npt::nerf
