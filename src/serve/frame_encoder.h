// The viewer's film: 1-sample passes accumulated into a running mean, tone-mapped (exposure, sRGB curve, 8 bits)
// and compressed to JPEG with TurboJPEG for the WebSocket.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/image.h"

namespace npt::serve {

class Accumulator {
  public:
    void reset(int width, int height);
    // Adds a pass (RGB or RGBA; RGBA is premultiplied, so it is shown over black) of the accumulator's size.
    void add(const Image& pass);
    int passes() const { return m_passes; }
    int width() const { return m_width; }
    int height() const { return m_height; }
    // The mean, tone-mapped: 8-bit sRGB, 3 bytes per pixel, row 0 at the top.
    void tonemap(double exposure_stops, std::vector<uint8_t>& rgb) const;

  private:
    int m_width = 0, m_height = 0, m_passes = 0;
    std::vector<float> m_sum;  // RGB
};

// Linear radiance -> 8-bit sRGB with exposure (the same curve as nerfpt render's PNG).
uint8_t tonemap_channel(float linear, float scale);

// JPEG of 8-bit RGB rows (TurboJPEG). Throws npt::Error when the encoder fails.
class JpegEncoder {
  public:
    JpegEncoder();
    ~JpegEncoder();
    JpegEncoder(const JpegEncoder&) = delete;
    JpegEncoder& operator=(const JpegEncoder&) = delete;
    std::string encode(const std::vector<uint8_t>& rgb, int width, int height, int quality = 85);

  private:
    void* m_handle = nullptr;
};

}  // namespace npt::serve
