#include "core/exr_header_check.h"

#include <cstdint>
#include <fstream>
#include <string>

#include "core/error.h"

namespace npt {

namespace {

constexpr uint32_t k_long_names = 0x400;  // version flags (OpenEXR file layout)
constexpr uint32_t k_multipart = 0x1000;

// A null-terminated string of at most `most` characters at the stream's position; false at end of file.
bool read_name(std::istream& in, size_t most, std::string* s, bool* too_long) {
    s->clear();
    *too_long = false;
    for (char c; in.get(c);) {
        if (c == '\0') return true;
        if (s->size() == most) {
            *too_long = true;
            return true;
        }
        s->push_back(c);
    }
    return false;
}

}  // namespace

void check_exr_header(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return;  // OpenEXR says why
    std::error_code ec;
    const uintmax_t file_size = std::filesystem::file_size(path, ec);
    if (ec) return;
    uint8_t start[8];
    if (!in.read(reinterpret_cast<char*>(start), 8)) return;  // too short: OpenEXR's error
    const uint32_t flags = uint32_t(start[5]) << 8 | uint32_t(start[6]) << 16 | uint32_t(start[7]) << 24;
    const size_t most = flags & k_long_names ? 255 : 31;
    const std::string file = path.string();
    // Headers: one, or with the multipart flag several, each a list of attributes ended by a null byte; the
    // multipart list ends with an empty header.
    for (int header = 0;; ++header) {
        int attributes = 0;
        for (;; ++attributes) {
            if (in.peek() == std::char_traits<char>::eof()) return;  // truncated: OpenEXR's error
            if (in.peek() == 0) {
                in.get();
                break;
            }
            std::string name, type;
            for (std::string* s : {&name, &type}) {
                bool too_long = false;
                if (!read_name(in, most, s, &too_long)) return;
                if (too_long)
                    throw Error(file + ": malformed EXR header (attribute name or type '" + *s + "...' longer than " +
                                std::to_string(most) + " characters)");
            }
            uint8_t b[4];
            if (!in.read(reinterpret_cast<char*>(b), 4)) return;
            const int32_t size =
                int32_t(uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24);
            const uintmax_t at = uintmax_t(in.tellg());
            if (size < 0 || uintmax_t(size) > file_size - at)
                throw Error(file + ": EXR header attribute '" + name + "' (" + type + ") claims " +
                            std::to_string(size) + " bytes, but the file has " + std::to_string(file_size - at) +
                            " after it");
            in.seekg(size, std::ios::cur);
        }
        if (!(flags & k_multipart) || attributes == 0) return;
    }
}

}  // namespace npt
