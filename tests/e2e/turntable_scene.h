// A synthetic phone capture with known poses, rendered by nerfpt's own path tracer: a textured box on a
// textured floor, filmed by a camera that spirals around it three times while rising (the three rings of a
// real capture, walked without stopping). The textures are random rectangles, rich in the corners SIFT finds;
// the box is saturated orange so that curate's automatic subject mask finds it, the floor grey.
#pragma once

#include <cstdint>
#include <filesystem>

#include "core/transform.h"
#include "scene/scene.h"

namespace npt::test {

struct TurntableSettings {
    int width = 320, height = 240;
    // Video frames over the whole spiral: 48 per turn, so that the frames curate keeps (every other one) are
    // 15 degrees apart, about as dense as a walk around an object (the beer video: ~11 degrees).
    int frames = 144;
    double turns = 3.0;
    // Rings from 20 to 50 degrees above the floor, as a person films an object on the floor (the beer
    // video's median elevation is 29 degrees).
    double elevation_low_deg = 20, elevation_high_deg = 50;
    double distance = 4.0;  // from the centre of the box
    double fov_y_deg = 45;
    int spp = 8;
    double fps = 24;
    // A feature-rich variant for the poses benchmark (docs/benchmarks.md, "How fast COLMAP can be"): finer,
    // denser rectangles on larger textures, so that SIFT finds thousands of corners per frame, as on the
    // richly textured tabletop of issue 16. The CI test keeps the plain scene.
    bool rich_texture = false;
};

// World +Y up (glTF), the box centred above the origin.
scene::Scene make_turntable_scene(bool rich_texture = false);

// Frame k's camera on the spiral, looking at the box's centre.
scene::Camera turntable_camera(const TurntableSettings& settings, int frame);

// The camera as an OpenGL camera-to-world matrix (columns right, up, backward, position), the convention of
// transforms.json.
Mat4 opengl_camera_to_world(const scene::Camera& camera);

// Renders every frame to folder/render_NNNNN.png and encodes them with ffmpeg (libx264) into `video`.
// Throws npt::Error when ffmpeg fails.
void render_turntable_video(const TurntableSettings& settings, const std::filesystem::path& folder,
                            const std::filesystem::path& video);

// The true poses as a transforms.json whose frames are named frame_NNNNN.png (NNNNN = video frame), as
// `nerfpt curate` names the frames it keeps, so that poses match by name.
void write_true_transforms(const TurntableSettings& settings, const std::filesystem::path& json);

}  // namespace npt::test
