// COLMAP's binary sparse model (cameras.bin, images.bin, points3D.bin), read without the COLMAP library, and
// the reprojection error that says whether a model (and our reading of it) is sound. Layout and conventions
// are in docs/formats.md, "COLMAP models and transforms.json from poses".
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/transform.h"

namespace npt::capture {

using Vec3d = std::array<double, 3>;
using Vec2d = std::array<double, 2>;

// The camera models nerfpt understands: the ones transforms.json can express (pinhole + OpenCV radial and
// tangential distortion). The values are COLMAP's model ids.
enum class CameraModel : int32_t {
    simple_pinhole = 0,
    pinhole = 1,
    simple_radial = 2,
    radial = 3,
    opencv = 4
};

const char* camera_model_name(CameraModel model);
// Number of parameters COLMAP stores for the model.
int camera_model_param_count(CameraModel model);

// Pinhole + OpenCV distortion, the common form of every supported model (absent terms are 0).
struct Intrinsics {
    double fx = 0, fy = 0, cx = 0, cy = 0;
    double k1 = 0, k2 = 0, p1 = 0, p2 = 0;
};

struct ColmapCamera {
    int32_t id = 0;
    CameraModel model = CameraModel::pinhole;
    uint64_t width = 0, height = 0;
    std::vector<double> params;  // as COLMAP stores them, camera_model_param_count(model) values

    Intrinsics intrinsics() const;
};

struct Point2D {
    double x = 0, y = 0;      // pixels, COLMAP convention: the top-left pixel's centre is (0.5, 0.5)
    int64_t point3d_id = -1;  // -1: not triangulated
};

struct ColmapImage {
    int32_t id = 0;
    // World-to-camera rotation as a unit quaternion (w, x, y, z) and translation: x_cam = R x_world + t, in
    // COLMAP's camera frame (OpenCV: +X right, +Y down, looks down +Z).
    std::array<double, 4> qvec{1, 0, 0, 0};
    Vec3d tvec{0, 0, 0};
    int32_t camera_id = 0;
    std::string name;  // relative to the image folder COLMAP was run on
    std::vector<Point2D> points2d;

    Mat4 world_to_camera() const;
    Mat4 camera_to_world() const;  // still COLMAP's camera axes
};

struct TrackElement {
    int32_t image_id = 0;
    int32_t point2d_idx = 0;
};

struct ColmapPoint3D {
    uint64_t id = 0;
    Vec3d xyz{0, 0, 0};
    std::array<uint8_t, 3> rgb{0, 0, 0};
    double error = 0;  // COLMAP's mean reprojection error of this point, pixels
    std::vector<TrackElement> track;
};

struct ColmapModel {
    std::vector<ColmapCamera> cameras;
    std::vector<ColmapImage> images;
    std::vector<ColmapPoint3D> points;

    const ColmapCamera* find_camera(int32_t id) const;
    const ColmapImage* find_image(int32_t id) const;
};

// Each reader throws npt::Error naming the file and the record when the file is missing, truncated, holds a
// count larger than the rest of the file could hold (checked before allocating), an unsupported camera model,
// or NaN/Inf.
std::vector<ColmapCamera> read_cameras_binary(const std::filesystem::path& file);
std::vector<ColmapImage> read_images_binary(const std::filesystem::path& file);
std::vector<ColmapPoint3D> read_points3d_binary(const std::filesystem::path& file);

// Reads folder/{cameras,images,points3D}.bin and checks that they agree: every image's camera exists, every
// track element names an existing image and one of its 2D points.
ColmapModel read_colmap_model(const std::filesystem::path& folder);

// Pixel position of a world point seen by `image` through `camera`, with COLMAP's distortion. The point must
// be in front of the camera (z > 0) for the result to mean anything.
Vec2d project(const ColmapCamera& camera, const ColmapImage& image, const Vec3d& world);

struct ReprojectionStats {
    size_t observations = 0;
    double mean_px = 0;
    double max_px = 0;
};

// Distance between every 3D point's projection and the 2D observations its track names. A model from
// read_colmap_model is consistent, so this does not throw.
ReprojectionStats reprojection_error(const ColmapModel& model);

}  // namespace npt::capture
