// Blur detection for the curate stage: the variance of the Laplacian of the grey image (a sharp frame has
// strong second derivatives at edges, a blurred one has few), and the rules that pick frames by that score.
#pragma once

#include <string>
#include <vector>

#include "capture/frame_source.h"

namespace npt::capture {

// A grey image in [0, 255], row-major.
struct Grey {
    int width = 0;
    int height = 0;
    std::vector<float> v;
    float at(int x, int y) const { return v[size_t(y) * size_t(width) + size_t(x)]; }
};

// Rec. 601 luma, box-downscaled by an integer factor so that the longest side is at most `max_side`
// (0: full size). Downscaling makes the score cheap and less sensitive to sensor noise.
Grey to_grey(const Frame8& frame, int max_side);
// Variance of the 3x3 Laplacian [0 1 0; 1 -4 1; 0 1 0] over the interior pixels; 0 for images under 3x3.
double laplacian_variance(const Grey& grey);

enum class SharpnessRule { Window, Threshold };

// Per candidate frame: kept, or the reason it was dropped (empty when kept).
struct Selection {
    std::vector<bool> kept;
    std::vector<std::string> reason;
    double mean = 0.0;
    double stddev = 0.0;
};

// Window rule (default): the candidates, in time order, are split into `target` equal windows; the
// sharpest frame of each window is kept unless its score is below mean - 2 sigma of all `all_scores`. This
// keeps coverage around the object uniform (COLMAP's sequential matcher needs overlapping neighbours),
// where a global threshold can drop a whole stretch of a walk that was filmed while moving fast.
// Threshold rule (the design paper): keep every candidate at or above mean - 1 sigma.
// `candidate` marks the frames still in the running (e.g. not dropped by the subject mask); the others keep
// their place in time but are never chosen.
Selection select_sharp(const std::vector<double>& all_scores, const std::vector<bool>& candidate,
                       SharpnessRule rule, int target);

}  // namespace npt::capture
