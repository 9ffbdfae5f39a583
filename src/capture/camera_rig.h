// Where the cameras of a transforms.json stand, seen from its origin (the centre of attention `nerfpt poses`
// puts there): what a turntable video needs to frame the object as the capture did.
#pragma once

#include <cstddef>
#include <filesystem>

namespace npt::capture {

struct RigSummary {
    size_t cameras = 0;
    double median_distance = 0;       // from the origin, world units
    double median_elevation_deg = 0;  // above the XY plane (+Z is up in transforms.json)
    double fov_x_deg = 0;             // horizontal field of view of the (first) camera
    int width = 0, height = 0;        // image size in pixels
};

// Reads only the JSON (no images). Throws npt::Error naming the file and the field when the frames, their
// transform_matrix, the image size (w/h) or the focal length (fl_x or camera_angle_x) are missing or invalid.
RigSummary summarize_rig(const std::filesystem::path& transforms_json);

}  // namespace npt::capture
