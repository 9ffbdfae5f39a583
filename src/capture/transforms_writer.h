// COLMAP poses to instant-ngp's transforms.json: OpenGL cameras, the average camera up turned to +z, the
// point the cameras look at moved to the origin and the scene scaled to a mean camera distance of 4, as
// instant-ngp's colmap2nerf.py does, so that its NeRF-synthetic-sized defaults fit a capture. docs/formats.md
// has the details.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "capture/colmap_model.h"
#include "core/transform.h"

namespace npt::capture {

struct TransformsSettings {
    // Where the images COLMAP was run on live (a relative path is relative to the json's folder); each
    // frame's file_path is this folder plus the image's name, written relative to the json's folder.
    std::filesystem::path images_folder = "images";
    // instant-ngp's scene extent in unit cubes. 16 was colmap2nerf's default for years (newer versions say
    // 32); a captured object with its background needs room beyond the unit cube.
    int aabb_scale = 16;
    // Mean distance of the cameras from the centre of attention after scaling (colmap2nerf: 4, about the
    // NeRF-synthetic cameras' distance).
    double mean_camera_distance = 4.0;
};

struct PosedFrame {
    std::string name;      // the COLMAP image name
    Mat4 camera_to_world;  // OpenGL camera (looks down -Z, +Y up), in the normalised world
    Intrinsics intrinsics;
    int width = 0, height = 0;
};

struct NerfPoses {
    std::vector<PosedFrame> frames;  // sorted by name
    // The similarity transform applied to COLMAP's world: a COLMAP world point p is at
    // world_from_colmap * p in the normalised world (e.g. to place points3D in the scene).
    Mat4 world_from_colmap;
    Vec3d centre_colmap{0, 0, 0};  // the centre of attention in COLMAP's world
};

// The normalised poses. Throws npt::Error when the model has no image or the cameras all sit at one point.
NerfPoses nerf_poses(const ColmapModel& model, const TransformsSettings& settings = {});

// Writes transforms.json for the model at `json_path`. Intrinsics are written once at the top when every
// image shares one camera, per frame otherwise. Throws npt::Error naming the file when it cannot be written.
void write_transforms(const ColmapModel& model, const std::filesystem::path& json_path,
                      const TransformsSettings& settings = {});

}  // namespace npt::capture
