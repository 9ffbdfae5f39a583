#include "media/nanovdb_layout.h"

#include <nanovdb/NanoVDB.h>  // for NANOVDB_MAJOR_VERSION_NUMBER only (no NanoVDB code runs here)

#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <vector>

#include "core/error.h"

namespace npt::media {
namespace {

// nanovdb/util/IO.h: a 16-byte segment header, then per grid a 176-byte record and its name, then the grids.
constexpr uint64_t k_magic = 0x304244566f6e614eULL;  // "NanoVDB0"
constexpr uint64_t k_header_bytes = 16, k_record_bytes = 176;
constexpr size_t k_file_size_at = 8, k_name_size_at = 136, k_codec_at = 168;  // fields of a record

template <typename T>
T field(const unsigned char* p, size_t at) {
    T v;
    std::memcpy(&v, p + at, sizeof(T));
    return v;
}

}  // namespace

void check_nanovdb_layout(const std::string& where) {
    std::ifstream in(where, std::ios::binary);
    in.seekg(0, std::ios::end);
    const auto end = in.tellg();
    if (!in || end <= 0) return;  // NanoVDB reports an unreadable or empty file
    const uint64_t size = uint64_t(end);
    in.seekg(0);
    const auto fail = [&](const std::string& why) {
        throw Error(where + ": cannot read NanoVDB file: " + why);
    };
    uint64_t pos = 0;
    for (int segment = 0;; ++segment) {
        // NanoVDB stops at a header it cannot read whole, and rejects a wrong magic number or version itself.
        if (size - pos < k_header_bytes) return;
        unsigned char header[k_header_bytes];
        in.read(reinterpret_cast<char*>(header), k_header_bytes);
        pos += k_header_bytes;
        if (field<uint64_t>(header, 0) != k_magic) return;
        const uint16_t grids = field<uint16_t>(header, 12), codec = field<uint16_t>(header, 14);
        const std::string seg = "segment " + std::to_string(segment);
        // NanoVDB's own message for another major version leaks the version string it formats.
        const uint32_t version = field<uint32_t>(header, 8), major = (version >> 21) & 0x7ff;
        if (major != NANOVDB_MAJOR_VERSION_NUMBER)
            fail(seg + ": NanoVDB format version " + std::to_string(major) + "." +
                 std::to_string((version >> 10) & 0x7ff) + "." + std::to_string(version & 0x3ff) +
                 ", this build reads version " + std::to_string(NANOVDB_MAJOR_VERSION_NUMBER) +
                 ".x (write the file again with a matching NanoVDB)");
        if (codec != 0) fail(seg + " is compressed; only uncompressed NanoVDB files are supported");
        uint64_t data = 0;
        for (uint16_t g = 0; g < grids; ++g) {
            const std::string what = seg + ", grid " + std::to_string(g);
            if (size - pos < k_record_bytes) fail("cut short in the metadata of " + what);
            unsigned char record[k_record_bytes];
            in.read(reinterpret_cast<char*>(record), k_record_bytes);
            pos += k_record_bytes;
            const uint32_t name_size = field<uint32_t>(record, k_name_size_at);
            if (name_size == 0 || name_size > size - pos)
                fail(what + ": a name of " + std::to_string(name_size) + " bytes does not fit in the file");
            std::vector<char> name(name_size);
            in.read(name.data(), name_size);
            pos += name_size;
            if (name.back() != '\0') fail(what + ": its name does not end in a zero byte");
            if (field<uint16_t>(record, k_codec_at) != 0)
                fail(what + " is compressed; only uncompressed NanoVDB files are supported");
            const uint64_t bytes = field<uint64_t>(record, k_file_size_at);
            if (bytes > std::numeric_limits<uint64_t>::max() - data)
                fail(what + ": size " + std::to_string(bytes));
            data += bytes;
        }
        if (data > size - pos)
            fail("cut short: the grids of " + seg + " need " + std::to_string(data) + " bytes, " +
                 std::to_string(size - pos) + " are left");
        pos += data;
        in.seekg(std::streamoff(pos));
    }
}

}  // namespace npt::media
