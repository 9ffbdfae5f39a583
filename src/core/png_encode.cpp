#include "core/png_encode.h"

#include <zlib.h>

#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.h"

namespace npt {
namespace {

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) out.push_back(uint8_t(v >> s));
}

// A chunk: length, type, data, CRC of type and data.
void put_chunk(std::vector<uint8_t>& out, const char type[4], const uint8_t* data, size_t size) {
    put_u32(out, uint32_t(size));
    const size_t start = out.size();
    out.insert(out.end(), type, type + 4);
    if (size) out.insert(out.end(), data, data + size);
    put_u32(out, uint32_t(crc32(0L, out.data() + start, uInt(out.size() - start))));
}

uint8_t paeth(int a, int b, int c) {
    const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
    return uint8_t(pa <= pb && pa <= pc ? a : (pb <= pc ? b : c));
}

}  // namespace

void encode_png(const std::filesystem::path& path, int width, int height, int channels, const uint8_t* pixels) {
    if (width <= 0 || height <= 0 || !(channels == 1 || channels == 3 || channels == 4))
        throw Error(path.string() + ": cannot write a PNG of " + std::to_string(width) + "x" + std::to_string(height) +
                    " with " + std::to_string(channels) + " channels");
    const size_t row = size_t(width) * size_t(channels);
    // Filtered scanlines: a filter byte (4: Paeth) and each byte minus its Paeth predictor.
    std::vector<uint8_t> filtered((row + 1) * size_t(height));
    for (size_t y = 0; y < size_t(height); ++y) {
        const uint8_t* cur = pixels + y * row;
        const uint8_t* up = y > 0 ? cur - row : nullptr;
        uint8_t* out = &filtered[y * (row + 1)];
        out[0] = 4;
        for (size_t i = 0; i < row; ++i) {
            const int a = i >= size_t(channels) ? cur[i - channels] : 0;
            const int b = up ? up[i] : 0;
            const int c = up && i >= size_t(channels) ? up[i - channels] : 0;
            out[1 + i] = uint8_t(cur[i] - paeth(a, b, c));
        }
    }
    uLongf packed_size = compressBound(uLong(filtered.size()));
    std::vector<uint8_t> packed(packed_size);
    if (compress2(packed.data(), &packed_size, filtered.data(), uLong(filtered.size()), 1) != Z_OK)
        throw Error(path.string() + ": cannot compress the PNG's pixels");

    std::vector<uint8_t> file = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    std::vector<uint8_t> ihdr;
    put_u32(ihdr, uint32_t(width));
    put_u32(ihdr, uint32_t(height));
    const uint8_t colour_type = channels == 1 ? 0 : (channels == 3 ? 2 : 6);
    ihdr.insert(ihdr.end(), {8, colour_type, 0, 0, 0});  // 8 bits, deflate, adaptive filters, no interlace
    put_chunk(file, "IHDR", ihdr.data(), ihdr.size());
    put_chunk(file, "IDAT", packed.data(), packed_size);
    put_chunk(file, "IEND", nullptr, 0);
    std::ofstream f(path, std::ios::binary);
    f.write(reinterpret_cast<const char*>(file.data()), std::streamsize(file.size()));
    f.close();
    if (!f) throw Error(path.string() + ": cannot write PNG (is the folder writable, the disk full?)");
}

}  // namespace npt
