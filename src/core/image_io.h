// Reading and writing image files: PNG/JPG/TGA/HDR through stb, EXR through OpenEXR. Writes go to a temporary
// file in the destination folder and are renamed into place, so a crash never leaves a half-written image.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/srgb.h"

namespace npt {

// Largest accepted width or height; checked before any pixel memory is allocated.
constexpr int k_max_image_side = 32768;

// Reads an image file into 3 (RGB) or 4 (RGBA) float channels. 8/16-bit formats are decoded through the sRGB
// EOTF when `srgb` is true (colour images), or scaled to [0, 1] as they are when false (data such as normal
// or roughness maps). HDR and EXR are scene-linear already and returned as stored. Throws npt::Error naming
// the file.
Image read_image(const std::filesystem::path& path, bool srgb = true);

// Width and height from the file's header, without decoding the pixels (PNG/JPG/TGA/HDR through stb).
// Throws npt::Error naming the file when it cannot be read.
struct ImageSize {
    int width = 0, height = 0;
};
ImageSize read_image_size(const std::filesystem::path& path);

// The same for an encoded file held in memory (a glTF .glb buffer view or data URI); `name` is for messages.
Image decode_image(const unsigned char* data, size_t size, const std::string& name, bool srgb = true);

// float32 RGB (alpha dropped), scene-linear, ZIP compression (lossless).
void write_exr(const std::filesystem::path& path, const Image& image);

// Another layer of an EXR file: channel names[c] holds channel c of *image (the main image's size), e.g.
// {"normal.X", "normal.Y", "normal.Z"}.
struct ExrLayer {
    std::vector<std::string> names;
    const Image* image = nullptr;
};

// Header attributes of a frame of a sequence (docs/formats.md): OpenEXR's standard framesPerSecond and
// worldToCamera, and nerfpt's own ("nerfpt.frame", "nerfpt.yfov", ...). Empty: none written.
struct ExrMetadata {
    double fps = 0.0;  // > 0: framesPerSecond, as a rational (24, 30000/1001 from 29.97...)
    bool has_camera = false;
    float world_to_camera[4][4] = {};  // row-major, OpenEXR's M44f convention (row vectors: p' = p M)
    std::vector<std::pair<std::string, int>> ints;
    std::vector<std::pair<std::string, float>> floats;
    std::vector<std::pair<std::string, std::string>> strings;
};

// float32, ZIP: channel c of `image` as names[c] for the first names.size() channels (the rest left out), then
// every layer's channels. Throws npt::Error naming the file and, for a bad layer, its first channel.
void write_exr_channels(const std::filesystem::path& path, const Image& image, const std::vector<std::string>& names,
                        const std::vector<ExrLayer>& layers = {}, const ExrMetadata* metadata = nullptr);

// float32, ZIP: R, G, B and, for a 4-channel image, A (written as it is: premultiplied if the image is), then
// every layer's channels. Throws npt::Error naming the file and, for a bad layer, its first channel.
void write_exr_layers(const std::filesystem::path& path, const Image& image, const std::vector<ExrLayer>& layers,
                      const ExrMetadata* metadata = nullptr);

// True when `path` is an OpenEXR file of width x height whose every channel reads back in full (a frame a
// sequence may skip); false for a missing, truncated, corrupt or differently sized file. Never throws.
bool exr_reads_back_whole(const std::filesystem::path& path, int width, int height);

// The header attributes write_exr_layers wrote (fps 0 and has_camera false where absent). Throws npt::Error.
ExrMetadata read_exr_metadata(const std::filesystem::path& path);

// 8-bit sRGB: value x 2^exposure_stops, sRGB OETF, clamped to [0, 1]; alpha dropped.
void write_png(const std::filesystem::path& path, const Image& image, float exposure_stops = 0.0f);

// The same for premultiplied RGBA (4 channels): an RGBA PNG with straight alpha (PNG's), the colour divided by
// alpha before the exposure and the sRGB curve; alpha 0 stores black.
void write_png_premultiplied(const std::filesystem::path& path, const Image& rgba, float exposure_stops = 0.0f);

// One channel of `image` as an 8-bit grey PNG, the value as it is (x 255, clamped to [0, 1], no sRGB curve):
// for data such as an alpha map.
void write_png_grey(const std::filesystem::path& path, const Image& image, int channel);

}  // namespace npt
