// Images (core/image_io.h): PNG, JPEG, TGA, BMP, PSD, GIF, HDR through stb from memory, and EXR (OpenEXR
// reads files) when the input starts with EXR's magic number.
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
    fuzz::refuse_or_load([&] { decode_image(data, size, "in", true); });
    return 0;
}
