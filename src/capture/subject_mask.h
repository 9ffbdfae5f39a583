// Where the filmed object is in a frame: an HSV colour threshold, the largest connected blob of the mask,
// and its centroid. Frames whose centroid strays far from the others (the camera looked away, someone walked
// through) are dropped before the sharpness selection.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "capture/frame_source.h"
#include "core/vec.h"

namespace npt::capture {

// H in degrees [0, 360), S and V in [0, 1]. When h_min > h_max the hue range wraps through 0 (red); only
// the automatic range produces that, user ranges must have min <= max in every channel.
struct HsvRange {
    float h_min = 0, s_min = 0, v_min = 0;
    float h_max = 360, s_max = 1, v_max = 1;
    bool contains(float h, float s, float v) const;
};

// The automatic range: the median H, S and V of the more saturated half of the pixels in the central 10% of
// the image (a centred square whose area is a tenth of the frame), widened by these tolerances. The person
// filming keeps the object in the middle, so the centre's most colourful pixels are the object's.
constexpr float k_auto_hue_tolerance = 20.0f;  // degrees
constexpr float k_auto_sv_tolerance = 0.25f;

void rgb_to_hsv(float r, float g, float b, float& h, float& s, float& v);  // r, g, b in [0, 1]
HsvRange automatic_range(const Frame8& frame);
// Throws npt::Error naming the option when a channel's min > max or a value is out of range.
void validate_range(const HsvRange& r);

struct MaskResult {
    std::optional<Vec2>
        centroid;  // of the largest 4-connected component, in pixels of `frame`; none if empty
    int component_pixels = 0;
};

// The mask is evaluated on a copy box-downscaled to at most `max_side` (0: full size); the centroid is
// returned in full-resolution pixel coordinates.
MaskResult subject_centroid(const Frame8& frame, const HsvRange& range, int max_side);

// Sigma multiple of the centroid rule, as in the design paper.
constexpr double k_centroid_sigmas = 8.0;

// For each frame: empty when its centroid is within k_centroid_sigmas of the centre of all centroids in
// both x and y, else the reason. The centre and sigma are the median and 1.4826 x the median absolute
// deviation: with the mean and standard deviation the outliers inflate sigma themselves, and no frame of
// n can ever be more than (n - 1) / sqrt(n) sigma away (under 8 for n < 66). Sigma is floored at
// `min_sigma` pixels so that a perfectly steady subject does not make every pixel of jitter an outlier.
std::vector<std::string> centroid_outliers(const std::vector<std::optional<Vec2>>& centroids,
                                           double min_sigma, Vec2& centre, Vec2& sigma);

}  // namespace npt::capture
