// The small parts of HTTP the server needs beyond Beast, as plain functions so that tests reach them: a URL
// path's percent-decoding and a Range header's one byte range (RFC 9110 14.1.2).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace npt::serve {

// "/a%20b.png" -> "/a b.png". Null for a malformed escape or one that decodes to NUL: such a path is not
// found.
std::optional<std::string> percent_decode_path(std::string_view path);
// The inverse for one path segment: everything but RFC 3986's unreserved characters escaped.
std::string percent_encode_segment(std::string_view segment);

struct ByteRange {
    enum class Kind {
        whole,          // no Range header, or one this server ignores (another unit, several ranges): 200
        partial,        // [first, last] of the file: 206
        unsatisfiable,  // starts past the end, or the file is empty: 416
    };
    Kind kind = Kind::whole;
    uint64_t first = 0, last = 0;  // inclusive, when partial
};

// The range a Range header asks of a file of `size` bytes: "bytes=A-B", "bytes=A-" and "bytes=-N". A syntax
// error makes the header ignored (the whole file), as RFC 9110 says. An open-ended range is cut to `max_span`
// bytes: a browser asks for "bytes=0-" and takes the rest in further requests, so a video is never read
// whole.
ByteRange parse_byte_range(std::string_view header, uint64_t size, uint64_t max_span);

}  // namespace npt::serve
