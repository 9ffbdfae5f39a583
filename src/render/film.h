// The film's outputs beside the colour image, on every backend: alpha (`--transparent`, Blender Cycles' Film >
// Transparent) and the AOV layers albedo, normal and depth (`--aov`), what the camera ray met first
// (render/first_hit.h). Their names in an EXR file follow the layer.channel convention of Blender and Nuke.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/image.h"

namespace npt::render {

// Which AOVs a render produces: a bit mask.
enum AovBits : uint32_t { k_aov_albedo = 1u, k_aov_normal = 2u, k_aov_depth = 4u };

// The AOV layers, each width x height and empty where not asked for: albedo 3 channels (linear base colour),
// normal 3 (world-space unit shading normal, averaged), depth 1 (distance along the camera ray; +inf where the
// pixel saw nothing).
struct AovImages {
    Image albedo, normal, depth;
    // The pixel's values into each layer that is allocated.
    void set(size_t pixel, Rgb albedo_value, Vec3 normal_value, float depth_value);
};

// The layers of `mask`, allocated (zero) at width x height; the others empty.
AovImages make_aov_images(int width, int height, uint32_t mask);

// "albedo,normal,depth" or any subset in any order -> a mask. Throws npt::Error naming the bad value (the
// command line puts "--aov: " in front).
uint32_t parse_aov_list(const std::string& text);

// An EXR layer: channels "<layer>.<channel>" in the order of the image's channels.
struct ExrLayerNames {
    const char* layer;
    std::vector<std::string> channels;
};
// albedo.R/G/B, normal.X/Y/Z, depth.Z.
ExrLayerNames aov_exr_names(AovBits aov);

}  // namespace npt::render
