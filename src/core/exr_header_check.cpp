#include "core/exr_header_check.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <vector>

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

// The types OpenEXR (3.1) reads by their own layout, whatever size the file states: for these a stated size
// that differs from the layout's puts OpenEXR's reading out of step with the sizes walked here, and it then
// takes a later value's bytes for the next attribute's size (a 297-byte file made it ask for 1.7 GB;
// fuzz_image).
int fixed_size(const std::string& type) {
    static const std::map<std::string, int> sizes = {
        {"box2i", 16},      {"box2f", 16},   {"chromaticities", 32},
        {"compression", 1}, {"double", 8},   {"envmap", 1},
        {"float", 4},       {"int", 4},      {"keycode", 28},
        {"lineOrder", 1},   {"m33f", 36},    {"m33d", 72},
        {"m44f", 64},       {"m44d", 128},   {"rational", 8},
        {"tiledesc", 9},    {"timecode", 8}, {"v2i", 8},
        {"v2f", 8},         {"v2d", 16},     {"v3i", 12},
        {"v3f", 12},        {"v3d", 24},     {"deepImageState", 1}};
    const auto it = sizes.find(type);
    return it == sizes.end() ? -1 : it->second;
}

int32_t int32_at(const uint8_t* p) {
    return int32_t(uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24);
}

// The bytes the layout of a variable-size value takes (chlist: named channel records and a null byte;
// preview: width, height and 4 bytes a pixel; stringvector: strings, each after its length), or -1 when it
// does not fit in `v`. Other types: v.size() (OpenEXR reads them by the stated size).
int64_t layout_size(const std::string& type, const std::vector<uint8_t>& v, size_t most_name) {
    const int64_t n = int64_t(v.size());
    if (type == "chlist") {
        int64_t at = 0;
        for (;;) {
            const void* end = at < n ? std::memchr(&v[size_t(at)], 0, size_t(n - at)) : nullptr;
            if (!end) return -1;
            const int64_t name = static_cast<const uint8_t*>(end) - &v[size_t(at)];
            at += name + 1;
            if (name == 0) return at;  // the list's end
            if (size_t(name) > most_name) return -1;
            at += 16;  // pixel type, linear flag and 3 reserved bytes, x and y sampling
            if (at > n) return -1;
        }
    }
    if (type == "preview") {
        if (n < 8) return -1;
        const uint64_t w = uint32_t(int32_at(&v[0])), h = uint32_t(int32_at(&v[4]));
        const uint64_t pixels = uint64_t(n - 8) / 4;  // what fits (division first: w * h may overflow)
        if (w != 0 && h > pixels / w) return -1;
        return int64_t(8 + 4 * w * h);
    }
    if (type == "stringvector") {
        int64_t at = 0;
        while (at < n) {
            if (n - at < 4) return -1;
            const int32_t len = int32_at(&v[size_t(at)]);
            at += 4;
            if (len < 0 || len > n - at) return -1;
            at += len;
        }
        return at;
    }
    return n;
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
                    throw Error(file + ": malformed EXR header (attribute name or type '" + *s +
                                "...' longer than " + std::to_string(most) + " characters)");
            }
            uint8_t b[4];
            if (!in.read(reinterpret_cast<char*>(b), 4)) return;
            const int32_t size =
                int32_t(uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24);
            const uintmax_t at = uintmax_t(in.tellg());
            if (size < 0 || uintmax_t(size) > file_size - at)
                throw Error(file + ": EXR header attribute '" + name + "' (" + type + ") claims " +
                            std::to_string(size) + " bytes, but the file has " +
                            std::to_string(file_size - at) + " after it");
            const int fixed = fixed_size(type);
            if (fixed >= 0 && size != fixed)
                throw Error(file + ": EXR header attribute '" + name + "' (" + type + ") claims " +
                            std::to_string(size) + " bytes; a " + type + " has " + std::to_string(fixed));
            std::vector<uint8_t> value(static_cast<size_t>(size));
            if (!in.read(reinterpret_cast<char*>(value.data()), size)) return;  // truncated: OpenEXR's error
            if (fixed < 0 && layout_size(type, value, most) != int64_t(size))
                throw Error(file + ": EXR header attribute '" + name + "' (" + type + ") claims " +
                            std::to_string(size) + " bytes, but its contents do not take exactly that many");
        }
        if (!(flags & k_multipart) || attributes == 0) return;
    }
}

}  // namespace npt
