#include "serve/frame_encoder.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <turbojpeg.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/srgb.h"

namespace npt::serve {

namespace {
constexpr size_t k_pixels_per_task = 1 << 15;
}  // namespace

void Accumulator::reset(int width, int height) {
    m_width = width;
    m_height = height;
    m_passes = 0;
    m_sum.assign(size_t(width) * size_t(height) * 3, 0.0f);
}

void Accumulator::add(const Image& pass) {
    if (pass.width != m_width || pass.height != m_height)
        throw Error("viewer: a " + std::to_string(pass.width) + "x" + std::to_string(pass.height) +
                    " pass for a " + std::to_string(m_width) + "x" + std::to_string(m_height) + " film");
    const size_t n = size_t(m_width) * size_t(m_height);
    const size_t c = size_t(pass.channels);
    // In parallel: at 1280x720 one thread took a few ms of every frame the viewer sends (the GPU's pass: ~10 ms).
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, k_pixels_per_task), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i)
            for (size_t k = 0; k < 3; ++k) {
                const float v = pass.pixels[i * c + k];
                m_sum[i * 3 + k] += std::isfinite(v) ? v : 0.0f;
            }
    });
    ++m_passes;
}

uint8_t tonemap_channel(float linear, float scale) {
    const float v = std::clamp(linear_to_srgb(std::max(0.0f, linear * scale)), 0.0f, 1.0f);
    return uint8_t(std::lround(v * 255.0f));
}

void Accumulator::tonemap(double exposure_stops, std::vector<uint8_t>& rgb) const {
    // A table over linear [0, 1] in steps of 1/16383: the sRGB curve's steepest slope (12.92) moves less than a
    // code value per step, and powf per channel cost ~15 ms a frame at 1280x720.
    constexpr int k_lut = 16384;
    static const std::vector<uint8_t> lut = [] {
        std::vector<uint8_t> t(k_lut);
        for (int i = 0; i < k_lut; ++i) t[size_t(i)] = tonemap_channel(float(i) / float(k_lut - 1), 1.0f);
        return t;
    }();
    rgb.resize(m_sum.size());
    const float scale = float(std::exp2(exposure_stops)) / float(std::max(1, m_passes)) * float(k_lut - 1);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, m_sum.size(), 3 * k_pixels_per_task),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i < r.end(); ++i) {
                              const float x = m_sum[i] * scale + 0.5f;
                              rgb[i] = x >= float(k_lut - 1) ? 255 : x > 0.0f ? lut[size_t(x)] : 0;
                          }
                      });
}

JpegEncoder::JpegEncoder() : m_handle(tjInitCompress()) {
    if (!m_handle) throw Error("viewer: TurboJPEG could not start: " + std::string(tjGetErrorStr2(nullptr)));
}

JpegEncoder::~JpegEncoder() {
    if (m_handle) tjDestroy(static_cast<tjhandle>(m_handle));
}

std::string JpegEncoder::encode(const std::vector<uint8_t>& rgb, int width, int height, int quality) {
    if (rgb.size() != size_t(width) * size_t(height) * 3) throw Error("viewer: JPEG input of the wrong size");
    unsigned char* out = nullptr;
    unsigned long size = 0;
    if (tjCompress2(static_cast<tjhandle>(m_handle), rgb.data(), width, 0, height, TJPF_RGB, &out, &size, TJSAMP_420,
                    quality, TJFLAG_FASTDCT) != 0) {
        const std::string why = tjGetErrorStr2(static_cast<tjhandle>(m_handle));
        tjFree(out);
        throw Error("viewer: JPEG encoding failed: " + why);
    }
    std::string bytes(reinterpret_cast<const char*>(out), size);
    tjFree(out);
    return bytes;
}

}  // namespace npt::serve
