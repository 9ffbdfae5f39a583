#include "core/image_io.h"

#include <ImfChannelList.h>
#include <ImfCompression.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfFloatAttribute.h>
#include <ImfIntAttribute.h>
#include <ImfMatrixAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>
#include <ImfStringAttribute.h>
#include <ImfThreading.h>
#include <stb_image.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <memory>
#include <random>
#include <system_error>
#include <thread>

#include "core/error.h"
#include "core/exr_header_check.h"
#include "core/memory.h"
#include "core/png_encode.h"
#include "core/temp_file.h"

namespace npt {
namespace fs = std::filesystem;

namespace {

void check_size(int w, int h, const std::string& name) {
    if (w <= 0 || h <= 0)
        throw Error(name + ": image has no pixels (" + std::to_string(w) + "x" + std::to_string(h) + ")");
    if (w > k_max_image_side || h > k_max_image_side)
        throw Error(name + ": image size " + std::to_string(w) + "x" + std::to_string(h) +
                    " exceeds the limit of " + std::to_string(k_max_image_side) + " per side");
}

// stb returns 1-4 channels; we keep RGB or RGBA.
template <typename T, typename Convert>
Image expand_channels(const T* src, int w, int h, int n, Convert convert) {
    int out_c = (n == 2 || n == 4) ? 4 : 3;
    Image img(w, h, out_c);
    size_t count = size_t(w) * size_t(h);
    for (size_t i = 0; i < count; ++i) {
        const T* s = src + i * size_t(n);
        float* d = img.pixels.data() + i * size_t(out_c);
        if (n <= 2) {
            d[0] = d[1] = d[2] = convert(s[0]);
            if (n == 2)
                d[3] = float(s[1]) / float(std::is_same_v<T, float> ? 1 : (sizeof(T) == 1 ? 255 : 65535));
        } else {
            for (int c = 0; c < 3; ++c) d[c] = convert(s[c]);
            if (n == 4)
                d[3] = float(s[3]) / float(std::is_same_v<T, float> ? 1 : (sizeof(T) == 1 ? 255 : 65535));
        }
    }
    return img;
}

struct StbFree {
    void operator()(void* p) const { stbi_image_free(p); }
};

Image decode_stb_sized(const unsigned char* data, size_t size, const std::string& name, bool srgb);

// The decoder's buffer and ours (float RGBA at most): a 32768x32768 image is allowed by its header and needs
// 20 GiB.
Image decode_stb(const unsigned char* data, size_t size, const std::string& name, bool srgb) {
    int w = 0, h = 0, n = 0;
    const bool known =
        size > 0 && size <= size_t(INT32_MAX) && stbi_info_from_memory(data, int(size), &w, &h, &n);
    const double bytes = known ? double(w) * double(h) * (4.0 * 4.0 + 4.0 * n) : 0.0;
    return with_memory_context(name + ": a " + std::to_string(w) + "x" + std::to_string(h) + " image", bytes,
                               "use a smaller image",
                               [&] { return decode_stb_sized(data, size, name, srgb); });
}

Image decode_stb_sized(const unsigned char* data, size_t size, const std::string& name, bool srgb) {
    if (size == 0) throw Error(name + ": file is empty");
    if (size > size_t(INT32_MAX)) throw Error(name + ": file is too large to decode");
    int len = int(size);
    int w = 0, h = 0, n = 0;
    if (!stbi_info_from_memory(data, len, &w, &h, &n)) {
        const char* why = stbi_failure_reason();
        throw Error(name + ": not a readable image (" + (why ? why : "unknown format") + ")");
    }
    check_size(w, h, name);
    if (stbi_is_hdr_from_memory(data, len)) {
        std::unique_ptr<float, StbFree> px(stbi_loadf_from_memory(data, len, &w, &h, &n, 0));
        if (!px) throw Error(name + ": cannot decode HDR image (" + std::string(stbi_failure_reason()) + ")");
        return expand_channels(px.get(), w, h, n, [](float v) { return v; });
    }
    if (stbi_is_16_bit_from_memory(data, len)) {
        std::unique_ptr<stbi_us, StbFree> px(stbi_load_16_from_memory(data, len, &w, &h, &n, 0));
        if (!px) throw Error(name + ": cannot decode image (" + std::string(stbi_failure_reason()) + ")");
        return expand_channels(px.get(), w, h, n, [srgb](stbi_us v) {
            float f = float(v) / 65535.0f;
            return srgb ? srgb_to_linear(f) : f;
        });
    }
    std::unique_ptr<stbi_uc, StbFree> px(stbi_load_from_memory(data, len, &w, &h, &n, 0));
    if (!px) throw Error(name + ": cannot decode image (" + std::string(stbi_failure_reason()) + ")");
    std::array<float, 256> lut;
    for (int i = 0; i < 256; ++i)
        lut[size_t(i)] = srgb ? srgb_to_linear(float(i) / 255.0f) : float(i) / 255.0f;
    return expand_channels(px.get(), w, h, n, [&lut](stbi_uc v) { return lut[v]; });
}

bool has_exr_magic(const unsigned char* data, size_t size) {
    return size >= 4 && data[0] == 0x76 && data[1] == 0x2f && data[2] == 0x31 && data[3] == 0x01;
}

Image read_exr(const fs::path& path) {
    const std::string name = path.string();
    check_exr_header(path);
    try {
        Imf::InputFile file(name.c_str());
        const Imath::Box2i dw = file.header().dataWindow();
        const long long w = (long long)dw.max.x - dw.min.x + 1, h = (long long)dw.max.y - dw.min.y + 1;
        if (w > k_max_image_side || h > k_max_image_side || w <= 0 || h <= 0)
            check_size(int(std::clamp<long long>(w, -1, 1LL << 30)),
                       int(std::clamp<long long>(h, -1, 1LL << 30)), name);
        const Imf::ChannelList& ch = file.header().channels();
        const bool rgb = ch.findChannel("R") && ch.findChannel("G") && ch.findChannel("B");
        const bool luma = !rgb && ch.findChannel("Y");
        if (!rgb && !luma) throw Error(name + ": EXR has neither R, G, B nor Y channels");
        const bool alpha = ch.findChannel("A") != nullptr;
        Image img(int(w), int(h), alpha ? 4 : 3);
        const size_t xs = sizeof(float) * size_t(img.channels), ys = xs * size_t(w);
        // The frame buffer is addressed with absolute data-window coordinates, hence the shifted base
        // pointer.
        char* base = reinterpret_cast<char*>(img.pixels.data()) - ptrdiff_t(dw.min.x) * ptrdiff_t(xs) -
                     ptrdiff_t(dw.min.y) * ptrdiff_t(ys);
        Imf::FrameBuffer fb;
        const char* names[3] = {"R", "G", "B"};
        // Y: one slice (a frame buffer holds one per name) into R, copied to G and B below.
        for (int c = 0; c < (rgb ? 3 : 1); ++c)
            fb.insert(rgb ? names[c] : "Y",
                      Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys, 1, 1, 0.0));
        if (alpha) fb.insert("A", Imf::Slice(Imf::FLOAT, base + 3 * sizeof(float), xs, ys, 1, 1, 1.0));
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        if (luma)
            for (size_t i = 0, n = size_t(w) * size_t(h); i < n; ++i) {
                float* px = img.pixels.data() + i * size_t(img.channels);
                px[1] = px[2] = px[0];
            }
        return img;
    } catch (const Error&) {
        throw;
    } catch (const std::bad_alloc&) {
        throw Error(name + ": not enough memory to read the EXR image (use a smaller image)");
    } catch (const std::exception& e) {
        std::string what = e.what();
        std::replace(what.begin(), what.end(), '\n', ' ');
        throw Error(name + ": cannot read EXR (" + what + ")");
    }
}

std::vector<unsigned char> read_bytes(const fs::path& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error(path.string() + ": file not found");
    if (fs::is_directory(path, ec)) throw Error(path.string() + ": is a folder, not an image");
    // A FIFO or a device (a texture named /dev/stdin) would block or never end.
    if (!fs::is_regular_file(path, ec)) throw Error(path.string() + ": not a regular file");
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(path.string() + ": cannot open");
    return std::vector<unsigned char>(std::istreambuf_iterator<char>(f), {});
}

// A sibling name unlikely to collide with a concurrent writer, so rename() is atomic in one file system.
fs::path temp_sibling(const fs::path& path) { return new_temp_path(path); }

void commit_temp(const fs::path& tmp, const fs::path& path) {
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw Error(path.string() + ": cannot move the written image into place (" + ec.message() + ")");
    }
}

void check_writable(const fs::path& path, const Image& image) {
    check_size(image.width, image.height, path.string());
    if (image.channels != 3 && image.channels != 4)
        throw Error(path.string() + ": cannot write an image with " + std::to_string(image.channels) +
                    " channels");
    if (image.pixels.size() != size_t(image.width) * size_t(image.height) * size_t(image.channels))
        throw Error(path.string() + ": image buffer size does not match its dimensions");
}

}  // namespace

Image decode_image(const unsigned char* data, size_t size, const std::string& name, bool srgb) {
    if (has_exr_magic(data, size)) throw Error(name + ": embedded EXR images are not supported");
    return decode_stb(data, size, name, srgb);
}

Image read_image(const fs::path& path, bool srgb) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error(path.string() + ": file not found");
    if (fs::is_directory(path, ec)) throw Error(path.string() + ": is a folder, not an image");
    // A FIFO or a device (a texture named /dev/stdin) would block or never end.
    if (!fs::is_regular_file(path, ec)) throw Error(path.string() + ": not a regular file");
    std::ifstream f(path, std::ios::binary);
    unsigned char magic[4] = {0, 0, 0, 0};
    f.read(reinterpret_cast<char*>(magic), 4);
    if (has_exr_magic(magic, size_t(f.gcount()))) return read_exr(path);
    std::vector<unsigned char> bytes = read_bytes(path);
    return decode_stb(bytes.data(), bytes.size(), path.string(), srgb);
}

ImageSize read_image_size(const fs::path& path) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error(path.string() + ": file not found");
    int w = 0, h = 0, n = 0;
    if (!stbi_info(path.string().c_str(), &w, &h, &n)) {
        const char* why = stbi_failure_reason();
        throw Error(path.string() + ": not a readable image (" + (why ? why : "unknown format") + ")");
    }
    check_size(w, h, path.string());
    return {w, h};
}

namespace {

// Channel c of `image` is written as names[c] (a name per channel).
void add_exr_channels(Imf::Header& header, Imf::FrameBuffer& fb, const Image& image,
                      const std::vector<std::string>& names) {
    const size_t xs = sizeof(float) * size_t(image.channels), ys = xs * size_t(image.width);
    // OpenEXR's Slice takes a non-const pointer even for writing; it only reads through it.
    char* base = const_cast<char*>(reinterpret_cast<const char*>(image.pixels.data()));
    for (size_t c = 0; c < names.size(); ++c) {
        header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
        fb.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xs, ys));
    }
}

void add_exr_metadata(Imf::Header& header, const ExrMetadata& m) {
    if (m.fps > 0) {
        // NTSC rates as OpenEXR's own guessExactFps would give them; others as n/1000.
        const double ntsc = std::round(m.fps) * 1000.0 / 1001.0;
        const Imf::Rational r = std::abs(m.fps - ntsc) < 1e-3 ? Imf::Rational(int(std::round(m.fps)) * 1000, 1001)
                                : m.fps == std::round(m.fps) ? Imf::Rational(int(m.fps), 1)
                                                             : Imf::Rational(int(std::round(m.fps * 1000)), 1000);
        Imf::addFramesPerSecond(header, r);
    }
    if (m.has_camera) Imf::addWorldToCamera(header, Imath::M44f(m.world_to_camera));
    for (const auto& [name, v] : m.ints) header.insert(name, Imf::IntAttribute(v));
    for (const auto& [name, v] : m.floats) header.insert(name, Imf::FloatAttribute(v));
    for (const auto& [name, v] : m.strings) header.insert(name, Imf::StringAttribute(v));
}

// OpenEXR compresses a file's line blocks in parallel on its global thread pool, which is empty unless asked
// for: a 1080p float EXR (ZIP) takes ~0.3 s on one core, a shot's frame writer waits on it.
int exr_threads() {
    static const int n = [] {
        const int hw = std::max(1, int(std::thread::hardware_concurrency()));
        Imf::setGlobalThreadCount(hw);
        return hw;
    }();
    return n;
}

}  // namespace

void write_exr_channels(const fs::path& path, const Image& image, const std::vector<std::string>& names,
                        const std::vector<ExrLayer>& layers, const ExrMetadata* metadata) {
    check_size(image.width, image.height, path.string());
    if (names.empty() || size_t(image.channels) < names.size() ||
        image.pixels.size() != size_t(image.width) * size_t(image.height) * size_t(image.channels))
        throw Error(path.string() + ": " + std::to_string(image.channels) + " channels, " +
                    std::to_string(names.size()) + " channel names (or a buffer of the wrong size)");
    for (const ExrLayer& l : layers) {
        const std::string what = path.string() + ": layer " + (l.names.empty() ? "''" : "'" + l.names[0] + "'");
        if (!l.image || l.names.empty() || l.image->channels != int(l.names.size()) ||
            l.image->width != image.width || l.image->height != image.height ||
            l.image->pixels.size() != size_t(image.width) * size_t(image.height) * l.names.size())
            throw Error(what + " does not match the image (size or channel names)");
    }
    const fs::path tmp = temp_sibling(path);
    try {
        Imf::Header header(image.width, image.height);
        header.compression() = Imf::ZIP_COMPRESSION;
        if (metadata) add_exr_metadata(header, *metadata);
        Imf::FrameBuffer fb;
        add_exr_channels(header, fb, image, names);
        for (const ExrLayer& l : layers) add_exr_channels(header, fb, *l.image, l.names);
        {
            Imf::OutputFile out(tmp.string().c_str(), header, exr_threads());
            out.setFrameBuffer(fb);
            out.writePixels(image.height);
        }
    } catch (const std::exception& e) {
        std::error_code ec;
        fs::remove(tmp, ec);
        std::string what = e.what();
        std::replace(what.begin(), what.end(), '\n', ' ');
        throw Error(path.string() + ": cannot write EXR (" + what + ")");
    }
    commit_temp(tmp, path);
}

namespace {

// The PNG into its temporary sibling `tmp` (removed again on failure); errors name the final path.
void write_png_file(const fs::path& tmp, const fs::path& path, int width, int height, int channels,
                    const unsigned char* pixels) {
    try {
        encode_png(tmp, width, height, channels, pixels);
    } catch (const Error&) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw Error(path.string() + ": cannot write PNG (is the folder writable, the disk full?)");
    }
}

unsigned char srgb_byte(float linear) {
    const float v = std::isfinite(linear) ? std::clamp(linear_to_srgb(std::max(linear, 0.0f)), 0.0f, 1.0f)
                                          : (linear > 0 ? 1.0f : 0.0f);
    return static_cast<unsigned char>(std::lround(v * 255.0f));
}

// out_channels 3: RGB, alpha dropped; 4: RGBA from premultiplied RGBA, straight alpha.
void write_png_channels(const fs::path& path, const Image& image, float exposure_stops, int out_channels) {
    check_writable(path, image);
    if (out_channels == 4 && image.channels != 4)
        throw Error(path.string() + ": an RGBA PNG needs a 4-channel image");
    const float scale = std::exp2(exposure_stops);
    const size_t oc = size_t(out_channels), ic = size_t(image.channels);
    std::vector<unsigned char> out(size_t(image.width) * size_t(image.height) * oc);
    for (size_t i = 0, n = size_t(image.width) * size_t(image.height); i < n; ++i) {
        const float* px = &image.pixels[i * ic];
        float straight = 1.0f;
        if (oc == 4) {
            const float a = std::isfinite(px[3]) ? std::clamp(px[3], 0.0f, 1.0f) : 0.0f;
            out[i * oc + 3] = static_cast<unsigned char>(std::lround(a * 255.0f));
            straight = a > 0.0f ? 1.0f / a : 0.0f;
        }
        for (size_t c = 0; c < 3; ++c) out[i * oc + c] = srgb_byte(px[c] * straight * scale);
    }
    const fs::path tmp = temp_sibling(path);
    write_png_file(tmp, path, image.width, image.height, out_channels, out.data());
    commit_temp(tmp, path);
}

}  // namespace

void write_exr(const fs::path& path, const Image& image) {
    check_writable(path, image);
    write_exr_channels(path, image, {"R", "G", "B"});  // alpha, if any, dropped
}

void write_exr_layers(const fs::path& path, const Image& image, const std::vector<ExrLayer>& layers,
                      const ExrMetadata* metadata) {
    check_writable(path, image);
    const std::vector<std::string> names = image.channels == 4 ? std::vector<std::string>{"R", "G", "B", "A"}
                                                               : std::vector<std::string>{"R", "G", "B"};
    write_exr_channels(path, image, names, layers, metadata);
}

bool exr_reads_back_whole(const fs::path& path, int width, int height) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) return false;
    try {
        check_exr_header(path);
        Imf::InputFile file(path.string().c_str());
        const Imath::Box2i dw = file.header().dataWindow();
        if (dw.max.x - dw.min.x + 1 != width || dw.max.y - dw.min.y + 1 != height) return false;
        if (!file.isComplete()) return false;
        // Every channel decoded: a block whose bytes are present but damaged fails here, not in a compositor.
        Imf::FrameBuffer fb;
        std::vector<std::vector<float>> planes;
        const size_t n = size_t(width) * size_t(height);
        for (auto c = file.header().channels().begin(); c != file.header().channels().end(); ++c) {
            planes.emplace_back(n);
            char* base = reinterpret_cast<char*>(planes.back().data()) -
                         (size_t(dw.min.x) + size_t(dw.min.y) * size_t(width)) * sizeof(float);
            fb.insert(c.name(), Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * size_t(width)));
        }
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        return true;
    } catch (const std::exception&) {
        return false;
    }
}

ExrMetadata read_exr_metadata(const fs::path& path) {
    ExrMetadata m;
    try {
        check_exr_header(path);
        Imf::InputFile file(path.string().c_str());
        const Imf::Header& h = file.header();
        if (Imf::hasFramesPerSecond(h)) m.fps = double(Imf::framesPerSecond(h));
        if (Imf::hasWorldToCamera(h)) {
            m.has_camera = true;
            const Imath::M44f w = Imf::worldToCamera(h);
            for (int r = 0; r < 4; ++r)
                for (int c = 0; c < 4; ++c) m.world_to_camera[r][c] = w[r][c];
        }
        for (auto a = h.begin(); a != h.end(); ++a) {
            if (const auto* i = dynamic_cast<const Imf::IntAttribute*>(&a.attribute())) m.ints.push_back({a.name(), i->value()});
            if (const auto* f = dynamic_cast<const Imf::FloatAttribute*>(&a.attribute()))
                m.floats.push_back({a.name(), f->value()});
            if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&a.attribute()))
                m.strings.push_back({a.name(), s->value()});
        }
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        std::string what = e.what();
        std::replace(what.begin(), what.end(), '\n', ' ');
        throw Error(path.string() + ": cannot read EXR header (" + what + ")");
    }
    return m;
}

void write_png(const fs::path& path, const Image& image, float exposure_stops) {
    write_png_channels(path, image, exposure_stops, 3);
}

void write_png_premultiplied(const fs::path& path, const Image& rgba, float exposure_stops) {
    write_png_channels(path, rgba, exposure_stops, 4);
}

void write_png_grey(const fs::path& path, const Image& image, int channel) {
    check_writable(path, image);
    if (channel < 0 || channel >= image.channels)
        throw Error(path.string() + ": no channel " + std::to_string(channel) + " in a " +
                    std::to_string(image.channels) + "-channel image");
    const size_t n = size_t(image.width) * size_t(image.height), ic = size_t(image.channels);
    std::vector<unsigned char> out(n);
    for (size_t i = 0; i < n; ++i) {
        const float v = image.pixels[i * ic + size_t(channel)];
        const float c = std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : 0.0f;
        out[i] = static_cast<unsigned char>(std::lround(c * 255.0f));
    }
    const fs::path tmp = temp_sibling(path);
    write_png_file(tmp, path, image.width, image.height, 1, out.data());
    commit_temp(tmp, path);
}

}  // namespace npt
