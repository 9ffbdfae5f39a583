#include "scene/obj_syntax.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>

#include "core/error.h"

namespace npt::scene {
namespace {

// 'text' (built by appending: GCC 12 warns falsely on "'" + std::string(...) under -O3, -Wrestrict).
std::string in_quotes(std::string_view s) {
    std::string q;
    q.reserve(s.size() + 2);
    q += '\'';
    q += s;
    q += '\'';
    return q;
}

// One line split into blank-separated tokens (a '#' starts a comment).
std::vector<std::string_view> tokens(std::string_view line) {
    if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    std::vector<std::string_view> out;
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
        const size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
        if (i > start) out.push_back(line.substr(start, i - start));
    }
    return out;
}

// Calls fn(line number, tokens) for every non-empty line.
template <typename Fn>
void for_each_line(std::string_view text, Fn&& fn) {
    size_t line_no = 0;
    for (size_t pos = 0; pos < text.size();) {
        size_t end = text.find('\n', pos);
        if (end == std::string_view::npos) end = text.size();
        ++line_no;
        const auto t = tokens(text.substr(pos, end - pos));
        if (!t.empty()) fn(line_no, t);
        pos = end + 1;
    }
}

class LineError {
  public:
    LineError(const std::string& file, size_t line, std::string_view key)
        : m_prefix(file + ": line " + std::to_string(line) + ": " + std::string(key) + ": ") {}
    [[noreturn]] void operator()(const std::string& what) const { throw Error(m_prefix + what); }

  private:
    std::string m_prefix;
};

// A finite number in the whole token (a leading '+' allowed, as C's strtod does).
bool parse_finite(std::string_view s, double* out) {
    if (!s.empty() && s[0] == '+') s.remove_prefix(1);
    double v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v)) return false;
    *out = v;
    return true;
}

void numbers(const std::vector<std::string_view>& t, size_t min, size_t max, const LineError& fail) {
    if (t.size() - 1 < min || t.size() - 1 > max)
        fail(min == max ? fmt::format("expected {} numbers, got {}", min, t.size() - 1)
                        : fmt::format("expected {} to {} numbers, got {}", min, max, t.size() - 1));
    for (size_t i = 1; i < t.size(); ++i) {
        double v;
        if (!parse_finite(t[i], &v))
            fail(in_quotes(t[i]) + " is not a finite number (NaN, Inf and out-of-range values are errors)");
    }
}

// Element counts: vertices, texture coordinates, normals.
using Counts = std::array<int64_t, 3>;
constexpr const char* k_element_names[3] = {"vertices", "texture coordinates", "normals"};

// Checks one OBJ index against the elements defined before it (negative) or in the whole file (positive).
void check_index(std::string_view s, int kind, const Counts& before, const Counts& total,
                 const LineError& fail) {
    const std::string name = k_element_names[kind];
    const std::string text(s);  // a named string: "..." + std::string(...) trips GCC 12's -Wrestrict
    if (s.empty()) fail("empty index (expected v, v/vt, v//vn or v/vt/vn)");
    int64_t v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec == std::errc::result_out_of_range) fail("index " + text + " is beyond 64 bits");
    if (ec != std::errc() || end != s.data() + s.size())
        fail(in_quotes(s) + " is not an integer index into the " + name);
    // tinyobjloader reads indices as int; OBJ counts from 1, and -1 is the last element so far.
    if (v > INT32_MAX || v < INT32_MIN) fail("index " + text + " is beyond 32 bits");
    if (v == 0) fail("index 0 (OBJ indices start at 1; negative ones count back from the last)");
    const int64_t have = v > 0 ? total[size_t(kind)] : before[size_t(kind)];
    if (v > 0 && v > have)
        fail("index " + text + " is out of range (the file has " + std::to_string(have) + " " + name + ")");
    if (v < 0 && -v > have)
        fail("relative index " + text + " is out of range (" + std::to_string(have) + " " + name +
             " before it)");
}

}  // namespace

std::vector<std::string> check_obj_text(std::string_view text, const std::string& file) {
    Counts total{0, 0, 0};
    for_each_line(text, [&](size_t, const std::vector<std::string_view>& t) {
        if (t[0] == "v") ++total[0];
        if (t[0] == "vt") ++total[1];
        if (t[0] == "vn") ++total[2];
    });
    Counts before{0, 0, 0};
    std::vector<std::string> mtllibs;
    for_each_line(text, [&](size_t line, const std::vector<std::string_view>& t) {
        const LineError fail(file, line, t[0]);
        if (t[0] == "v") {
            numbers(t, 3, 7, fail);  // x y z [w] or x y z r g b
            ++before[0];
        } else if (t[0] == "vt") {
            numbers(t, 1, 3, fail);
            ++before[1];
        } else if (t[0] == "vn") {
            numbers(t, 3, 3, fail);
            ++before[2];
        } else if (t[0] == "f" || t[0] == "l" || t[0] == "p") {
            const size_t min = t[0] == "f" ? 3 : t[0] == "l" ? 2 : 1;
            if (t.size() - 1 < min)
                fail(fmt::format("expected at least {} vertices, got {}", min, t.size() - 1));
            for (size_t i = 1; i < t.size(); ++i) {
                // v, v/vt, v//vn or v/vt/vn
                const std::string_view corner = t[i];
                if (std::count(corner.begin(), corner.end(), '/') > 2)
                    fail(in_quotes(corner) + " has more than three parts (v/vt/vn)");
                const size_t s1 = corner.find('/');
                check_index(corner.substr(0, s1), 0, before, total, fail);
                if (s1 == std::string_view::npos) continue;
                const std::string_view rest = corner.substr(s1 + 1);
                const size_t s2 = rest.find('/');
                const std::string_view uv = rest.substr(0, s2);
                if (!uv.empty() || s2 == std::string_view::npos) check_index(uv, 1, before, total, fail);
                if (s2 == std::string_view::npos) continue;
                check_index(rest.substr(s2 + 1), 2, before, total, fail);
            }
        } else if (t[0] == "mtllib") {
            for (size_t i = 1; i < t.size(); ++i) mtllibs.emplace_back(t[i]);
        }
    });
    return mtllibs;
}

void check_mtl_text(std::string_view text, const std::string& file) {
    for_each_line(text, [&](size_t line, const std::vector<std::string_view>& t) {
        const std::string_view key = t[0];
        const LineError fail(file, line, key);
        if (key == "Ka" || key == "Kd" || key == "Ks" || key == "Ke" || key == "Kt" || key == "Tf") {
            // "Ka spectral file.rfl" and "Ka xyz x y z" are other forms tinyobjloader skips.
            if (t.size() > 1 && (t[1] == "spectral" || t[1] == "xyz")) return;
            numbers(t, 1, 3, fail);
        } else if (key == "Ns" || key == "Ni" || key == "d" || key == "Tr" || key == "illum") {
            // "d -halo 0.5" is a valid form.
            if (key == "d" && t.size() > 1 && t[1] == "-halo") return;
            numbers(t, 1, 1, fail);
        }
    });
}

}  // namespace npt::scene
