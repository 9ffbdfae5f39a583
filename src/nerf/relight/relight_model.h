// What a relightable model adds to a NeRF (model file section "relight", docs/formats.md): the intrinsic
// network's configuration and parameters (intrinsic_field.h) and the estimate of the light the capture was
// filmed in: a small HDR environment and an exposure per training image. Models without it render emissive.
#pragma once

#include <cstdint>
#include <vector>

#include "core/vec.h"
#include "nerf/relight/intrinsic_field.h"

namespace npt::nerf {

struct IntrinsicConfig {
    HashGridConfig grid{12, 2, 17, 16, 1.5f};  // levels, features, log2 table, base resolution (scale derived)
    float finest_resolution = 1024.0f;          // times aabb_scale, as EncodingConfig
    int width = 64;
    int hidden_layers = 2;
    // New models shade with Burley's diffuse, as the Cycles renders the dev set was made with; the section's
    // header says which (absent: layered, the first models).
    IntrinsicDiffuse diffuse = IntrinsicDiffuse::burley;
};

// The capture environment: equirectangular in MODEL space directions, rows from +Z (v = 0) to -Z (v = 1),
// u = atan2(d.y, d.x) / 2pi + 0.5 (relight_env.h maps both ways); linear radiance in the images' units.
struct CaptureEnvironment {
    int width = 0, height = 0;
    std::vector<Rgb> texels;  // width * height, row-major
};

struct RelightFields {
    IntrinsicConfig config;
    std::vector<float> params;  // IntrinsicLayout order: the MLP's weights, then the hash grid
    CaptureEnvironment capture_env;
    std::vector<Rgb> exposure;  // per training image, multiplies its predicted colour (1 = the mean image)
    uint64_t steps = 0;         // optimiser steps of the relight stage
    double seconds = 0;         // its wall time
};

IntrinsicLayout make_intrinsic_layout(const IntrinsicConfig& config, float aabb_scale);

}  // namespace npt::nerf
