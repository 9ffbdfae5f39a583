// The model file's "RLIT" section (docs/formats.md): a relightable model's intrinsic network, capture
// environment and exposures. Payload: u64 length of a JSON header, the header (version, the intrinsic network's
// config, counts), then little-endian float32 arrays: the network's parameters, the environment's texels (RGB),
// the exposures (RGB). Files without the section load as emissive models; readers that predate it skip it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "nerf/relight/relight_model.h"

namespace npt::nerf {

std::vector<uint8_t> encode_relight_section(const RelightFields& fields, float aabb_scale);

// Throws npt::Error "<source>: relight section: <what>" on anything malformed: bad JSON, out-of-range config
// values, counts that do not match the payload, NaN or Inf, negative radiance.
RelightFields decode_relight_section(const uint8_t* data, size_t size, const std::string& source, float aabb_scale);

}  // namespace npt::nerf
