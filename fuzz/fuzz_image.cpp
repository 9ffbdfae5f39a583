// Images (core/image_io.h): PNG, JPEG, TGA, BMP, PSD, GIF, HDR through stb from memory, and EXR (OpenEXR
// reads files) when the input starts with EXR's magic number.
//
// Inputs whose header declares more than 2^18 pixels are skipped: a mutated header asks for up to the allowed
// 32768 x 32768, and the loader then zero-fills an image of that size before finding the data missing (perf on
// this harness: 93% of its time in memset's page faults; EXR seeds ran at 5-15 executions a second). The code
// that decodes is the same at any size; the size limits themselves are the unit tests' (image_io_test.cpp).
#include <stb_image.h>

#include <cstdint>
#include <cstring>

#include "core/image_io.h"
#include "harness_support.h"

namespace {

constexpr double k_max_pixels = double(1 << 18);

// The data window of an EXR header (its attributes: name\0 type\0 int32 size, value), or false when the header
// does not hold a well-formed one: then the loader sees the input as it is.
bool exr_pixels(const uint8_t* data, size_t size, double* pixels) {
    size_t i = 8;  // magic number and version
    auto cstring = [&](size_t* end) {
        const void* z = i < size ? std::memchr(data + i, 0, size - i) : nullptr;
        if (!z) return false;
        *end = size_t(static_cast<const uint8_t*>(z) - data);
        return true;
    };
    while (i < size && data[i] != 0) {
        size_t name_end = 0, type_end = 0;
        if (!cstring(&name_end)) return false;
        const bool window = std::strcmp(reinterpret_cast<const char*>(data + i), "dataWindow") == 0;
        i = name_end + 1;
        if (!cstring(&type_end)) return false;
        i = type_end + 1;
        int32_t len = 0;
        if (size - i < 4) return false;
        std::memcpy(&len, data + i, 4);
        i += 4;
        if (len < 0 || size - i < size_t(len)) return false;
        if (window && len == 16) {
            int32_t box[4];
            std::memcpy(box, data + i, 16);
            *pixels = (double(box[2]) - box[0] + 1.0) * (double(box[3]) - box[1] + 1.0);
            return true;
        }
        i += size_t(len);
    }
    return false;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace npt;
    (void)fuzz::scratch();
    if (size >= 4 && std::memcmp(data, "\x76\x2f\x31\x01", 4) == 0) {
        double pixels = 0.0;
        if (exr_pixels(data, size, &pixels) && pixels > k_max_pixels) return 0;
        const auto path = fuzz::put("in.exr", data, size);
        fuzz::refuse_or_load([&] { read_image(path); });
        return 0;
    }
    int w = 0, h = 0, n = 0;
    const bool sized = size <= (1u << 30) && stbi_info_from_memory(data, int(size), &w, &h, &n);
    if (sized && double(w) * double(h) > k_max_pixels) return 0;
    fuzz::refuse_or_load([&] { decode_image(data, size, "in", true); });
    return 0;
}
