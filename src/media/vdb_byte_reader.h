// Bounded little-endian reads of an OpenVDB file for the checks that run before OpenVDB reads it
// (openvdb_layout.h, openvdb_grid_check.h): every read and skip first checks that the bytes are there (in the
// file, or in the one grid's byte range being walked), so a size field is tested before anything trusts it.
#pragma once

#include <cstdint>
#include <fstream>
#include <string>

#include "core/error.h"

namespace npt::media {

class VdbByteReader {
  public:
    explicit VdbByteReader(const std::string& where) : m_where(where), m_in(where, std::ios::binary) {
        m_in.seekg(0, std::ios::end);
        const auto end = m_in.tellg();
        m_size = end > 0 ? uint64_t(end) : 0;
        m_end = m_size;
        m_in.seekg(0);
    }
    uint64_t size() const { return m_size; }
    uint64_t pos() const { return m_pos; }
    uint64_t left() const { return m_end - m_pos; }

    // Reads from now on stay inside [from, to) (a grid's byte range, to <= size()); limit(0, size()) lifts it.
    // `range` names the range in errors.
    void limit(uint64_t from, uint64_t to, const std::string& range) {
        m_end = to;
        m_range = range;
        seek(from);
    }
    bool ok() const { return bool(m_in); }

    // "<file>: cannot read OpenVDB file: <why>"
    [[noreturn]] void fail(const std::string& why) const {
        throw Error(m_where + ": cannot read OpenVDB file: " + why);
    }
    void need(uint64_t n, const std::string& what) const {
        if (n <= left()) return;
        const std::string at = what + " needs " + std::to_string(n) + " bytes at byte " + std::to_string(m_pos);
        if (m_end < m_size) fail(at + ", past the end of " + m_range + " at byte " + std::to_string(m_end));
        fail("cut short: " + at + ", the file has " + std::to_string(m_size));
    }
    template <typename T>
    T read(const std::string& what) {
        need(sizeof(T), what);
        T v;
        m_in.read(reinterpret_cast<char*>(&v), sizeof(T));
        m_pos += sizeof(T);
        return v;
    }
    void read_bytes(void* to, uint64_t n, const std::string& what) {
        need(n, what);
        m_in.read(static_cast<char*>(to), std::streamsize(n));
        m_pos += n;
    }
    void skip(uint64_t n, const std::string& what) {
        need(n, what);
        seek(m_pos + n);
    }
    void seek(uint64_t to) {  // callers seek only to offsets checked against the file
        m_pos = to;
        m_in.seekg(std::streamoff(to));
    }
    // OpenVDB's readString: a uint32 length, then the bytes.
    std::string string(const std::string& what) {
        const uint32_t n = read<uint32_t>(what);
        need(n, what);
        std::string s(n, '\0');
        read_bytes(s.data(), n, what);
        return s;
    }

  private:
    std::string m_where, m_range;
    std::ifstream m_in;
    uint64_t m_size = 0, m_end = 0, m_pos = 0;
};

}  // namespace npt::media
