#include "serve/http_util.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <limits>

namespace npt::serve {
namespace {

int hex_digit(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
    return s;
}

// All digits, no sign, no overflow.
std::optional<uint64_t> parse_u64(std::string_view s) {
    if (s.empty()) return std::nullopt;
    uint64_t v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
    return v;
}

}  // namespace

std::optional<std::string> percent_decode_path(std::string_view path) {
    std::string out;
    out.reserve(path.size());
    for (size_t i = 0; i < path.size(); ++i) {
        char c = path[i];
        if (c == '%') {
            if (i + 2 >= path.size()) return std::nullopt;
            const int hi = hex_digit(path[i + 1]), lo = hex_digit(path[i + 2]);
            if (hi < 0 || lo < 0) return std::nullopt;
            c = char(hi * 16 + lo);
            i += 2;
        }
        if (c == '\0') return std::nullopt;
        out += c;
    }
    return out;
}

std::string percent_encode_segment(std::string_view segment) {
    static const char* digits = "0123456789ABCDEF";
    std::string out;
    for (const char c : segment) {
        const auto u = static_cast<unsigned char>(c);
        if ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' ||
            c == '.' || c == '_' || c == '~') {
            out += c;
        } else {
            out += '%';
            out += digits[u >> 4];
            out += digits[u & 15];
        }
    }
    return out;
}

ByteRange parse_byte_range(std::string_view header, uint64_t size, uint64_t max_span) {
    ByteRange r;
    header = trim(header);
    constexpr std::string_view unit = "bytes=";
    if (header.size() < unit.size()) return r;
    for (size_t i = 0; i < unit.size(); ++i)
        if (char(std::tolower(static_cast<unsigned char>(header[i]))) != unit[i]) return r;
    const std::string_view spec = trim(header.substr(unit.size()));
    if (spec.find(',') != std::string_view::npos) return r;  // several ranges: the whole file (allowed)
    const size_t dash = spec.find('-');
    if (dash == std::string_view::npos) return r;
    const std::string_view a = trim(spec.substr(0, dash)), b = trim(spec.substr(dash + 1));
    if (a.empty()) {  // the last N bytes
        const auto n = parse_u64(b);
        if (!n) return r;
        if (*n == 0 || size == 0) return {ByteRange::Kind::unsatisfiable, 0, 0};
        r.kind = ByteRange::Kind::partial;
        r.first = *n >= size ? 0 : size - *n;
        r.last = size - 1;
        return r;
    }
    const auto first = parse_u64(a);
    if (!first) return r;
    std::optional<uint64_t> last;
    if (!b.empty()) {
        last = parse_u64(b);
        if (!last || *last < *first) return r;  // invalid: ignored
    }
    if (*first >= size) return {ByteRange::Kind::unsatisfiable, 0, 0};
    r.kind = ByteRange::Kind::partial;
    r.first = *first;
    const uint64_t span = std::max<uint64_t>(max_span, 1);
    const uint64_t open_last =
        *first > std::numeric_limits<uint64_t>::max() - span ? size - 1 : *first + span - 1;
    r.last = std::min(last ? *last : open_last, size - 1);
    return r;
}

}  // namespace npt::serve
