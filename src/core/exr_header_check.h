// Checks an OpenEXR file's header before OpenEXR reads it. OpenEXR allocates each attribute's value from the
// size the file states (up to 2 GB) before it finds the file too short, so a 300-byte corrupt file could make a
// reader allocate gigabytes (found by fuzz_image). Here every attribute's size is checked against the bytes
// that follow it in the file, and, for the types OpenEXR reads by their own layout (fixed-size values, channel
// lists, previews, string vectors), against that layout: OpenEXR does not check the two agree, and where they
// differ its reading falls out of step and takes a later value's bytes for the next size.
#pragma once

#include <filesystem>

namespace npt {

// Throws npt::Error naming the file and the attribute when an attribute's name or type is malformed or its value
// reaches past the end of the file. Returns quietly otherwise, and for what it does not know how to walk (left
// to OpenEXR's own checks).
void check_exr_header(const std::filesystem::path& path);

}  // namespace npt
