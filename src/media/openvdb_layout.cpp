#include "media/openvdb_layout.h"

#include <cstdint>
#include <fstream>

#include "core/error.h"

namespace npt::media {
namespace {

constexpr int64_t k_openvdb_magic = 0x56444220;  // OPENVDB_MAGIC (" BDV")

// Little-endian reads that know how many bytes are left (OpenVDB writes native order; every platform it runs
// on is little-endian).
class LayoutReader {
  public:
    explicit LayoutReader(const std::string& where) : m_where(where), m_in(where, std::ios::binary) {
        m_in.seekg(0, std::ios::end);
        const auto end = m_in.tellg();
        m_size = end > 0 ? uint64_t(end) : 0;
        m_in.seekg(0);
    }
    uint64_t size() const { return m_size; }
    uint64_t pos() const { return m_pos; }
    bool ok() const { return bool(m_in); }

    void need(uint64_t n, const std::string& what) const {
        if (n > m_size - m_pos)
            throw Error(m_where + ": cannot read OpenVDB file: cut short: " + what + " needs " +
                        std::to_string(n) + " bytes at byte " + std::to_string(m_pos) + ", the file has " +
                        std::to_string(m_size));
    }
    template <typename T>
    T read(const std::string& what) {
        need(sizeof(T), what);
        T v;
        m_in.read(reinterpret_cast<char*>(&v), sizeof(T));
        m_pos += sizeof(T);
        return v;
    }
    void skip(uint64_t n, const std::string& what) {
        need(n, what);
        seek(m_pos + n);
    }
    void seek(uint64_t to) {
        m_pos = to;
        m_in.seekg(std::streamoff(to));
    }
    // OpenVDB's readString: a uint32 length, then the bytes.
    std::string string(const std::string& what) {
        const uint32_t n = read<uint32_t>(what);
        need(n, what);
        std::string s(n, '\0');
        m_in.read(s.data(), n);
        m_pos += n;
        return s;
    }

  private:
    std::string m_where;
    std::ifstream m_in;
    uint64_t m_size = 0, m_pos = 0;
};

}  // namespace

void check_openvdb_layout(const std::string& where) {
    LayoutReader r(where);
    if (!r.ok() || r.size() < 12) return;  // OpenVDB says "not a VDB file" or "could not open"
    if (r.read<int64_t>("magic") != k_openvdb_magic) return;
    const uint32_t version = r.read<uint32_t>("file version");
    if (version < 218) return;  // older headers differ; OpenVDB reads them
    r.skip(8, "library version");
    const bool has_offsets = r.read<char>("header") != 0;
    if (version >= 220 && version < 222) r.skip(1, "header");  // per-file compression flag
    r.skip(36, "file UUID");

    const uint32_t meta_count = r.read<uint32_t>("file metadata count");
    for (uint32_t i = 0; i < meta_count; ++i) {
        const std::string what = "file metadata " + std::to_string(i);
        r.string(what + " name");
        r.string(what + " type");
        r.skip(r.read<uint32_t>(what + " size"), what + " value");
    }
    if (!has_offsets) return;  // a stream written without a seekable target: OpenVDB reads it in one pass

    const int32_t grids = r.read<int32_t>("grid count");
    if (grids < 0) throw Error(where + ": cannot read OpenVDB file: grid count " + std::to_string(grids));
    for (int32_t i = 0; i < grids; ++i) {
        const std::string what = "grid descriptor " + std::to_string(i);
        const std::string name = r.string(what + " name");
        r.string("grid '" + name + "' type");
        r.string("grid '" + name + "' instance parent");
        const int64_t grid_pos = r.read<int64_t>("grid '" + name + "' offsets");
        const int64_t block_pos = r.read<int64_t>("grid '" + name + "' offsets");
        const int64_t end_pos = r.read<int64_t>("grid '" + name + "' offsets");
        if (grid_pos < int64_t(r.pos()) || block_pos < grid_pos || end_pos < block_pos)
            throw Error(where + ": cannot read OpenVDB file: grid '" + name + "': offsets " +
                        std::to_string(grid_pos) + ", " + std::to_string(block_pos) + ", " +
                        std::to_string(end_pos) + " are out of order");
        if (uint64_t(end_pos) > r.size())
            throw Error(where + ": cannot read OpenVDB file: cut short: grid '" + name + "' ends at byte " +
                        std::to_string(end_pos) + ", the file has " + std::to_string(r.size()));
        r.seek(uint64_t(end_pos));
    }
}

}  // namespace npt::media
