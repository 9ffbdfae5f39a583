// The images `nerfpt eval` and `nerfpt view` make besides the render itself: a data set's ground truth as the
// metrics see it, the side-by-side comparison with an error heat map, and the step that lets values which
// are already sRGB-encoded (NeRF renders and training images) go through write_png unchanged.
#pragma once

#include <cstddef>

#include "core/image.h"
#include "nerf/dataset.h"

namespace npt::nerf {

// Frame `index` of `data` as RGB floats in [0, 1], composited over `background` on the stored (sRGB-encoded)
// values: rgb * a + background * (1 - a), as NeRF papers build their targets and as render_view composites.
// Throws npt::Error when index is out of range.
Image ground_truth_image(const Dataset& data, size_t index, Rgb background);

// Per pixel, mean over RGB of |a - b| times `gain`, clamped to [0, 1], through a black-red-yellow-white ramp
// (sRGB-encoded display values). Throws npt::Error when the sizes differ.
Image error_heat_map(const Image& a, const Image& b, float gain);

// An RGBA render (colour over `background`, alpha = coverage, as render_view returns it) put over `plate`
// instead: rgb + (plate - background) * (1 - alpha), on the stored sRGB-encoded values as NeRF composites.
// For an isolated object scored against photos of its room, the photo's own surroundings show through where
// the object does not cover. RGB out. Throws npt::Error when the sizes differ or the render has no alpha.
Image over_plate(const Image& render, Rgb background, const Image& plate);

// [ground truth | render | error heat map (gain 4)], three RGB panels side by side.
Image comparison_strip(const Image& ground_truth, const Image& render);

// core/image_io's write_png applies the sRGB OETF to linear light. Images here already hold sRGB-encoded
// values, so they are decoded with the inverse curve first: write_png(path, encoded_to_linear(img)) stores
// the values as they are (to within 8-bit rounding). RGB only; alpha is dropped.
Image encoded_to_linear(const Image& encoded);

}  // namespace npt::nerf
