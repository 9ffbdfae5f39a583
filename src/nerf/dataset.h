// A NeRF training set read from a `transforms.json` (instant-ngp / nerfstudio conventions): posed pinhole
// cameras and their images as 8-bit RGBA, plus the scene-normalisation numbers instant-ngp keeps beside them.
// Defaults follow instant-ngp, so its NeRF-synthetic and nerfstudio exports load unchanged.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/transform.h"
#include "core/vec.h"
#include "nerf/lens_distortion.h"
#include "nerf/train_pixel.h"

namespace npt::nerf {

// A pinhole camera as transforms.json stores it. camera_to_world is the OpenGL convention of NeRF-synthetic
// and instant-ngp (the camera looks down its -Z axis, +Y is up in the image). The OpenCV distortion is
// applied by generate_pixel_ray, so training, eval and view all see the photo's own (distorted) pixels.
struct Camera {
    Mat4 camera_to_world;
    float fx = 0, fy = 0;  // focal lengths in pixels
    float cx = 0, cy = 0;  // principal point in pixels, from the image's top-left corner
    int width = 0, height = 0;
    float k1 = 0, k2 = 0, p1 = 0, p2 = 0;  // OpenCV radial / tangential distortion

    LensDistortion distortion() const { return {k1, k2, p1, p2}; }
};

struct Dataset {
    std::vector<Camera> cameras;
    std::vector<std::string> names;  // each frame's `file_path` as written in the json
    std::filesystem::path source;    // the transforms.json read
    std::vector<std::filesystem::path> image_files;  // each frame's image as found on disk
    // All images, 8-bit RGBA, row-major from the top-left, image after image: 4 bytes per pixel keeps a few
    // hundred training views in memory where float RGBA would need four times as much. Pixels are the stored
    // (sRGB-encoded) values, not linearised: NeRFs are trained on them as they are.
    std::vector<uint8_t> rgba;
    int width = 0, height = 0;  // every frame has this size
    float aabb_scale = 1.0f;    // instant-ngp: the scene's bounding box is aabb_scale times the unit cube
    // instant-ngp maps a camera position p to p * scale + offset; 0.33 and (0.5, 0.5, 0.5) are the values it
    // uses for NeRF-synthetic, so they are the defaults when the json names none.
    float scale = 0.33f;
    Vec3 offset{0.5f, 0.5f, 0.5f};
    // Empty, or one per image: where the subject is seen (subject_focus.h); training draws its share of rays
    // there (training.subject_rays). Pixel coordinates of this size: set after downscaling.
    std::vector<PixelRect> subject_rects;

    size_t image_bytes() const { return size_t(width) * size_t(height) * 4; }
    const uint8_t* image(size_t i) const { return rgba.data() + i * image_bytes(); }
};

// Called with (frames loaded, total frames); from worker threads, but never two calls at once.
using ProgressFn = std::function<void(size_t done, size_t total)>;

// Largest total pixel memory a data set may need; checked before allocating, so a json with absurd sizes
// fails with a message instead of taking the machine's memory.
constexpr size_t k_max_dataset_bytes = size_t(32) << 30;

// instant-ngp's largest aabb_scale (8 occupancy cascades).
constexpr double k_max_aabb_scale = 128;

// Reads `folder_or_json/transforms_{split}.json` when given a folder (`transforms.json` when split is empty, or
// when split is "train" and the folder has transforms.json but no transforms_train.json),
// or the file itself when given a file (split is then ignored). Image paths are relative to the json; a path
// without an extension is tried with .png, .jpg and .jpeg. Images load in parallel. Throws npt::Error naming
// the file, the frame and the field.
// max_frames > 0 keeps at most that many frames, evenly spread over the json's (the live-training page's few
// held-out views: it need not decode a whole test set).
Dataset load_dataset(const std::filesystem::path& folder_or_json, const std::string& split,
                     const ProgressFn& progress = {}, size_t max_frames = 0);

// Shrinks every image by an integer factor (box filter over premultiplied colour, so transparent pixels do not
// bleed their colour into the edges) and scales the intrinsics to match. Sizes that are not multiples of the
// factor lose their last rows/columns. Throws npt::Error when factor < 1 or larger than the image.
void downscale_dataset(Dataset& ds, int factor);

// The world-space ray through image coordinates (px, py) of the (distorted) photo: pixel centres are at +0.5,
// y runs down the image. The pixel is undistorted with the camera's k1, k2, p1, p2 (Newton iteration,
// lens_distortion.h); with all four exactly 0 the pinhole ray comes out bit for bit as before. The direction
// is normalised; the origin is the camera position.
Ray generate_pixel_ray(const Camera& camera, float px, float py);

}  // namespace npt::nerf
