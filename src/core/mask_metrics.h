// Scores a predicted coverage (a NeRF's alpha, 1 - transmittance) against a ground-truth object mask, for
// `nerfpt eval --masks`: IoU, the DAVIS boundary F-measure and leak (coverage outside the object, the measure
// of floaters and of a table left under it). Masks are read from PNG files here too.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "core/image.h"

namespace npt {

// A binary image, row-major from the top-left; on[i] is 0 or 1.
struct Mask {
    int width = 0, height = 0;
    std::vector<uint8_t> on;
};

// A coverage image: values in [0, 1], row-major from the top-left.
struct Coverage {
    int width = 0, height = 0;
    std::vector<float> values;
};

// Pixels whose value is > threshold (the metrics' 0.5 for both the prediction and the ground truth).
Mask threshold_coverage(const Coverage& coverage, float threshold = 0.5f);

// |a and b| / |a or b|; 1 when both are empty (nothing predicted where there is nothing: a perfect score, as
// DAVIS counts it).
double mask_iou(const Mask& a, const Mask& b);

// DAVIS's seg2bmap: a pixel is a boundary pixel when it differs from its right, lower or lower-right
// neighbour (on both sides of an edge, one pixel thick); the image border is not a boundary (in the last row
// only the right neighbour counts, in the last column only the lower one, the last pixel never).
Mask mask_boundary(const Mask& mask);

// Pixels within Euclidean distance `radius` of a set pixel (a binary dilation with the disk x^2 + y^2 <= r^2,
// skimage's disk(r)); exact, through a distance transform, so its cost does not grow with the radius.
Mask dilate_mask(const Mask& mask, double radius);

// DAVIS's boundary tolerance for an image: ceil(0.008 * diagonal) pixels (9 for 540x960, 1 for 32x32).
int boundary_tolerance(int width, int height);

struct BoundaryScore {
    double precision = 0, recall = 0, f = 0;
};

// DAVIS's boundary measure F: the boundaries of prediction and truth (mask_boundary) are matched within
// `tolerance` pixels (dilate_mask); precision = matched predicted boundary pixels / predicted ones, recall
// the same for the truth's, F = 2PR / (P + R) (0 when both are 0). No boundary in one of them: P = 1, R = 0
// (no prediction) or P = 0, R = 1 (no truth); none in either: 1, 1.
BoundaryScore boundary_f(const Mask& predicted, const Mask& truth, int tolerance);

// Leak: the mean predicted coverage (clamped to [0, 1]) over the pixels farther than `margin` pixels from the
// truth's object (outside dilate_mask(truth, margin)); 0 when no pixel is that far. The margin keeps the
// truth's own edge error (anti-aliasing, a mask a pixel off) out of what should measure floaters and tables.
constexpr int k_leak_margin = 5;
double mask_leak(const Coverage& predicted, const Mask& truth, int margin = k_leak_margin);

// The mean predicted coverage (clamped to [0, 1]) over the truth's object pixels: how solid the object is
// where it should be. "psnr in mask over the photo" fills whatever the render leaves transparent with the
// photo itself, which flatters a partly transparent object; this says how much it filled. NaN when the mask
// is empty.
double mask_coverage_inside(const Coverage& predicted, const Mask& truth);

struct MaskScores {
    double iou = 0;
    BoundaryScore boundary;
    double leak = 0;
};

// All three for a predicted coverage against a truth mask: IoU and boundary F of predicted > 0.5, with
// boundary_tolerance of the image.
MaskScores score_mask(const Coverage& predicted, const Mask& truth);

// PSNR (data range 1, RGB) of a against b over the pixels the mask covers: the object's own quality, whatever
// surrounds it. Throws npt::Error when the sizes differ or the mask covers nothing; +infinity where equal.
double psnr_inside(const Image& a, const Image& b, const Mask& mask);

// Reads a mask file (PNG, or anything read_image reads; 8 or 16 bit, values taken as stored, no sRGB curve):
// its alpha channel when it has one that is not opaque everywhere, else grey (the mean of R, G, B). Throws
// npt::Error naming the file when it is missing or unreadable.
Coverage read_coverage(const std::filesystem::path& path);

// Box-filters coverage down by an integer factor, as downscale_dataset shrinks images (trailing rows and
// columns that do not fill a box are dropped). Throws npt::Error when factor < 1 or larger than the image.
Coverage downscale_coverage(const Coverage& coverage, int factor);

// All of the above throw npt::Error when two images' sizes differ.

}  // namespace npt
