#include "core/json_file.h"

#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "core/error.h"

namespace npt {
namespace {

// "line L, column C" of a byte offset (0-based) in `text`, 1-based as editors count.
std::string position(std::string_view text, size_t offset) {
    offset = std::min(offset, text.size());
    size_t line = 1, column = 1;
    for (size_t i = 0; i < offset; ++i) {
        if (text[i] == '\n') {
            ++line;
            column = 1;
        } else {
            ++column;
        }
    }
    return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

// nlohmann's messages start with "[json.exception.parse_error.101] "; the rest is one readable line.
std::string strip_prefix(const std::string& what) {
    const size_t p = what.find("] ");
    if (what.rfind("[json.exception", 0) == 0 && p != std::string::npos) return what.substr(p + 2);
    return what;
}

}  // namespace

void check_json_depth(std::string_view text, const std::string& name, bool comments) {
    int depth = 0;
    const size_t n = text.size();
    for (size_t i = 0; i < n; ++i) {
        const char c = text[i];
        switch (c) {
            case '"':  // a string: skip to its closing quote, over escapes
                for (++i; i < n && text[i] != '"'; ++i)
                    if (text[i] == '\\') ++i;
                break;
            case '[':
            case '{':
                if (++depth > k_max_json_depth)
                    throw Error(name + ": arrays and objects nested deeper than " +
                                std::to_string(k_max_json_depth) + " levels (" + position(text, i) + ")");
                break;
            case ']':
            case '}':
                if (depth > 0) --depth;
                break;
            case '/':
                if (!comments || i + 1 >= n) break;
                if (text[i + 1] == '/') {
                    while (i < n && text[i] != '\n') ++i;
                } else if (text[i + 1] == '*') {
                    const size_t end = text.find("*/", i + 2);
                    i = end == std::string_view::npos ? n : end + 1;
                }
                break;
            default:
                break;
        }
    }
}

nlohmann::json parse_json_text(std::string_view text, const std::string& name, bool comments) {
    check_json_depth(text, name, comments);
    try {
        return nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/true, comments);
    } catch (const nlohmann::json::parse_error& e) {  // its message has the line and column
        throw Error(name + ": not valid JSON: " + strip_prefix(e.what()));
    } catch (const nlohmann::json::exception& e) {
        // Number overflow (1e400) is out_of_range.406 with no position; the message quotes the number, so
        // find it in the text to say where.
        std::string what = strip_prefix(e.what());
        const size_t q = what.find('\'');
        const size_t q2 = q == std::string::npos ? q : what.find('\'', q + 1);
        if (q2 != std::string::npos && q2 > q + 1) {
            const size_t at = text.find(what.substr(q + 1, q2 - q - 1));
            if (at != std::string_view::npos) what += " (" + position(text, at) + ")";
        }
        throw Error(name + ": not valid JSON: " + what);
    }
}

nlohmann::json read_json_file(const std::filesystem::path& path, bool comments) {
    const std::string name = path.string();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error(name + ": no such file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(name + ": cannot read");
    std::stringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw Error(name + ": cannot read");
    const std::string text = ss.str();
    if (text.find_first_not_of(" \t\r\n") == std::string::npos) throw Error(name + ": file is empty");
    return parse_json_text(text, name, comments);
}

void check_msgpack_depth(const uint8_t* data, size_t size, const std::string& name) {
    // Elements still to read in each open map or array; the bottom entry is the one top-level value.
    std::vector<uint64_t> open{1};
    size_t pos = 0;
    // A big-endian length of `bytes` bytes; false when the data ends first (the parser will say so).
    const auto length = [&](int bytes, uint64_t* out) {
        if (size - pos < size_t(bytes)) return false;
        uint64_t v = 0;
        for (int k = 0; k < bytes; ++k) v = (v << 8) | data[pos++];
        *out = v;
        return true;
    };
    while (!open.empty()) {
        if (open.back() == 0) {
            open.pop_back();
            continue;
        }
        --open.back();
        if (pos >= size) return;
        const uint8_t b = data[pos++];
        uint64_t children = 0, skip = 0, len = 0;
        if (b <= 0x7f || b >= 0xe0) {  // positive and negative fixint
        } else if (b <= 0x8f) {
            children = 2 * uint64_t(b & 0x0f);  // fixmap: key and value
        } else if (b <= 0x9f) {
            children = b & 0x0f;  // fixarray
        } else if (b <= 0xbf) {
            skip = b & 0x1f;  // fixstr
        } else {
            switch (b) {
                case 0xc0:  // nil, false, true
                case 0xc2:
                case 0xc3:
                    break;
                case 0xc4:  // bin 8/16/32, str 8/16/32
                case 0xd9:
                    if (!length(1, &skip)) return;
                    break;
                case 0xc5:
                case 0xda:
                    if (!length(2, &skip)) return;
                    break;
                case 0xc6:
                case 0xdb:
                    if (!length(4, &skip)) return;
                    break;
                case 0xc7:  // ext 8/16/32: length, then a type byte
                    if (!length(1, &len)) return;
                    skip = len + 1;
                    break;
                case 0xc8:
                    if (!length(2, &len)) return;
                    skip = len + 1;
                    break;
                case 0xc9:
                    if (!length(4, &len)) return;
                    skip = len + 1;
                    break;
                case 0xcc:  // uint8, int8
                case 0xd0:
                    skip = 1;
                    break;
                case 0xcd:
                case 0xd1:
                    skip = 2;
                    break;
                case 0xca:
                case 0xce:
                case 0xd2:
                    skip = 4;
                    break;
                case 0xcb:
                case 0xcf:
                case 0xd3:
                    skip = 8;
                    break;
                case 0xd4:  // fixext 1/2/4/8/16: a type byte and the data
                    skip = 2;
                    break;
                case 0xd5:
                    skip = 3;
                    break;
                case 0xd6:
                    skip = 5;
                    break;
                case 0xd7:
                    skip = 9;
                    break;
                case 0xd8:
                    skip = 17;
                    break;
                case 0xdc:  // array 16/32
                    if (!length(2, &children)) return;
                    break;
                case 0xdd:
                    if (!length(4, &children)) return;
                    break;
                case 0xde:  // map 16/32
                    if (!length(2, &children)) return;
                    children *= 2;
                    break;
                case 0xdf:
                    if (!length(4, &children)) return;
                    children *= 2;
                    break;
                default:  // 0xc1 is never used: malformed
                    return;
            }
        }
        if (skip > size - pos) return;
        pos += size_t(skip);
        if (children > 0) {
            if (open.size() > size_t(k_max_json_depth))
                throw Error(name + ": maps and arrays nested deeper than " +
                            std::to_string(k_max_json_depth) + " levels (at byte " + std::to_string(pos) +
                            ")");
            open.push_back(children);
        }
    }
}

}  // namespace npt
