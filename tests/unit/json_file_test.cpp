// core/json_file: the one JSON/MessagePack entry point. Nesting is bounded before any recursive code runs
// (100 000 nested arrays crashed the glTF and snapshot readers), and every parse error names the file and
// where in it.
#include "core/json_file.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/error.h"
#include "test_support.h"

namespace npt {
namespace {

TEST(JsonFile, DepthIsBoundedWithoutRecursion) {
    const std::string ok = std::string(k_max_json_depth, '[') + std::string(k_max_json_depth, ']');
    EXPECT_NO_THROW(check_json_depth(ok, "ok.json"));
    EXPECT_NO_THROW(parse_json_text(ok, "ok.json"));
    const std::string deep = std::string(100000, '[') + std::string(100000, ']');
    test::expect_error_message([&] { parse_json_text(deep, "deep.json"); },
                               {"deep.json", "nested deeper than 256 levels", "line 1, column 257"});
    // Objects count too, brackets inside strings and comments do not.
    std::string objects;
    for (int i = 0; i < 300; ++i) objects += "{\"a\":";
    test::expect_error_message([&] { check_json_depth(objects, "o.json"); }, {"o.json", "nested deeper"});
    const std::string in_string = "[\"" + std::string(1000, '[') + "\\\"" + std::string(1000, '{') + "\"]";
    EXPECT_NO_THROW(parse_json_text(in_string, "s.json"));
    const std::string in_comment =
        "// " + std::string(1000, '[') + "\n/* " + std::string(1000, '{') + " */ [1]";
    EXPECT_NO_THROW(parse_json_text(in_comment, "c.json", /*comments=*/true));
}

TEST(JsonFile, ErrorsNameTheFileAndThePlace) {
    test::expect_error_message(
        [] { parse_json_text("{\n  \"a\": 1e400\n}", "big.json"); },
        {"big.json", "not valid JSON", "number overflow", "1e400", "line 2, column 8"});
    test::expect_error_message([] { parse_json_text("{\"a\": [1, 2}", "bad.json"); },
                               {"bad.json", "not valid JSON", "line 1"});
    const auto dir = test::temp_dir();
    test::expect_error_message([&] { read_json_file(dir / "none.json"); }, {"none.json", "no such file"});
    test::write_file(dir / "empty.json", " \n");
    test::expect_error_message([&] { read_json_file(dir / "empty.json"); }, {"empty.json", "empty"});
    test::write_file(dir / "ok.json", "{\"a\": [1, 2]}");
    EXPECT_EQ(read_json_file(dir / "ok.json")["a"][1], 2);
}

std::vector<uint8_t> nested_msgpack(size_t depth, uint8_t open) {
    std::vector<uint8_t> b(depth, open);  // fixarray/fixmap of one element, nested
    b.push_back(0xc0);                    // nil at the bottom (a fixmap would need a key and a value)
    return b;
}

TEST(JsonFile, MessagePackDepthIsBounded) {
    const auto deep = nested_msgpack(200000, 0x91);
    test::expect_error_message([&] { check_msgpack_depth(deep.data(), deep.size(), "deep.msgpack"); },
                               {"deep.msgpack", "nested deeper than 256 levels"});
    const auto ok = nested_msgpack(k_max_json_depth, 0x91);
    EXPECT_NO_THROW(check_msgpack_depth(ok.data(), ok.size(), "ok.msgpack"));
    EXPECT_NO_THROW(EXPECT_TRUE(nlohmann::json::from_msgpack(ok).is_array()));  // GCC ignores (void) here
    // Maps: key then value; the key is a fixstr, the value the next level.
    std::vector<uint8_t> maps;
    for (int i = 0; i < 1000; ++i) maps.insert(maps.end(), {0x81, 0xa1, 'k'});
    maps.push_back(0x01);
    test::expect_error_message([&] { check_msgpack_depth(maps.data(), maps.size(), "m"); }, {"m", "nested"});
    // Counts far larger than the data, truncated and malformed input: no error here (the parser reports
    // them), and no allocation or long loop for the claimed count.
    const std::vector<uint8_t> huge = {0xdd, 0xff, 0xff, 0xff, 0xff, 0x01};
    EXPECT_NO_THROW(check_msgpack_depth(huge.data(), huge.size(), "h"));
    const std::vector<uint8_t> bad = {0x92, 0xc1, 0xc1};
    EXPECT_NO_THROW(check_msgpack_depth(bad.data(), bad.size(), "b"));
    const std::vector<uint8_t> str = {0x92, 0xdb, 0xff, 0xff, 0xff, 0xff};
    EXPECT_NO_THROW(check_msgpack_depth(str.data(), str.size(), "s"));
    EXPECT_NO_THROW(check_msgpack_depth(nullptr, 0, "empty"));
}

}  // namespace
}  // namespace npt
