// The server's small HTTP helpers (serve/http_util.h): a URL path's percent-decoding (what the capture
// report's allow-list is compared with) and a Range header's byte range (a <video> seeks with them).
#include <gtest/gtest.h>

#include "serve/http_util.h"

namespace npt::serve {
namespace {

TEST(ServeHttp, PercentDecodingAndEncoding) {
    EXPECT_EQ(percent_decode_path("/capture/eval/a%20b.png"), "/capture/eval/a b.png");
    EXPECT_EQ(percent_decode_path("/capture/%2e%2E/x"), "/capture/../x");  // decoded, then only compared
    EXPECT_EQ(percent_decode_path("/plain"), "/plain");
    EXPECT_FALSE(percent_decode_path("/a%2"));    // truncated escape
    EXPECT_FALSE(percent_decode_path("/a%zz"));   // not hex
    EXPECT_FALSE(percent_decode_path("/a%00b"));  // NUL
    EXPECT_EQ(percent_encode_segment("r_0 (1)/..png"), "r_0%20%281%29%2F..png");
    EXPECT_EQ(percent_decode_path("/" + percent_encode_segment("ä ?#%")), "/ä ?#%");
}

TEST(ServeHttp, ByteRanges) {
    using K = ByteRange::Kind;
    const auto r = [](const char* h, uint64_t size, uint64_t max_span = 1000) {
        return parse_byte_range(h, size, max_span);
    };
    auto b = r("bytes=10-19", 100);
    EXPECT_EQ(b.kind, K::partial);
    EXPECT_EQ(b.first, 10u);
    EXPECT_EQ(b.last, 19u);
    b = r("bytes=90-500", 100);  // clipped to the file
    EXPECT_EQ(b.kind, K::partial);
    EXPECT_EQ(b.last, 99u);
    b = r("bytes=0-", 100);
    EXPECT_EQ(b.last, 99u);
    b = r("bytes=0-", 100000, 4096);  // open-ended: at most max_span bytes
    EXPECT_EQ(b.last, 4095u);
    b = r("bytes=0-99999", 100000, 4096);  // an explicit end is honoured
    EXPECT_EQ(b.last, 99999u);
    b = r("bytes=-5", 100);  // the last 5
    EXPECT_EQ(b.kind, K::partial);
    EXPECT_EQ(b.first, 95u);
    EXPECT_EQ(b.last, 99u);
    b = r("bytes=-500", 100);
    EXPECT_EQ(b.first, 0u);
    EXPECT_EQ(r("bytes=100-", 100).kind, K::unsatisfiable);
    EXPECT_EQ(r("bytes=0-", 0).kind, K::unsatisfiable);
    EXPECT_EQ(r("bytes=-0", 100).kind, K::unsatisfiable);
    // Ignored (the whole file, 200): other units, several ranges, syntax errors, a reversed range, overflow.
    for (const char* h : {"items=0-5", "bytes=0-5,10-20", "bytes=abc", "bytes=5", "bytes=9-3", "bytes=-",
                          "bytes=+1-2", "bytes=99999999999999999999999-", ""})
        EXPECT_EQ(r(h, 100).kind, K::whole) << h;
    EXPECT_EQ(r("Bytes=1-2", 100).kind, K::partial);  // the unit is case-insensitive
}

}  // namespace
}  // namespace npt::serve
