// Images (core/image_io.h): PNG, JPEG, TGA, BMP, PSD, GIF, HDR through stb from memory, and EXR (OpenEXR
// reads files) when the input starts with EXR's magic number.
//
// Inputs whose header declares more than 2^22 pixels are skipped: a mutated header claims up to the allowed
// 32768 x 32768, and stb then decodes a billion pixels of nothing (a JPEG's MCUs one by one) for seconds, which
// held the harness at 4 executions a second. The decoding code is the same at any size; the sizes themselves
// (limits, memory errors) are the unit tests' (image_io_test.cpp).
#include <stb_image.h>

#include <cstring>

#include "core/image_io.h"
#include "harness_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace npt;
    (void)fuzz::scratch();
    if (size >= 4 && std::memcmp(data, "\x76\x2f\x31\x01", 4) == 0) {
        const auto path = fuzz::put("in.exr", data, size);
        fuzz::refuse_or_load([&] { read_image(path); });
        return 0;
    }
    int w = 0, h = 0, n = 0;
    const bool sized = size <= (1u << 30) && stbi_info_from_memory(data, int(size), &w, &h, &n);
    if (sized && double(w) * double(h) > double(1 << 22)) return 0;
    fuzz::refuse_or_load([&] { decode_image(data, size, "in", true); });
    return 0;
}
