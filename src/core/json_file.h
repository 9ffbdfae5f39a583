// The one way JSON (and MessagePack) input is parsed, with the project's one-line errors: every message names
// the file, says where in it (line and column), and nothing a hostile file holds can crash the reader.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace npt {

// Deepest nesting of arrays and objects (maps) a JSON or MessagePack input may have. nlohmann's text parser
// is iterative, but its MessagePack reader, copies, dump() and tinygltf's conversion of `extras` recurse once
// per level, so 100 000 nested arrays overflow the stack. Real files nest fewer than 20 levels.
constexpr int k_max_json_depth = 256;

// Throws npt::Error "NAME: arrays and objects nested deeper than 256 levels (line L, column C)" when the JSON
// text nests deeper than k_max_json_depth. Strings (with escapes) are skipped, and with `comments` so are
// // and /* */ comments. Malformed text is left to the parser: this only bounds the depth, in one pass.
void check_json_depth(std::string_view text, const std::string& name, bool comments = false);

// Parses JSON text after check_json_depth. Errors are one line naming `name` (a file, or "FILE: field" for
// JSON stored inside another file): "NAME: not valid JSON: <reason> (line L, column C)", including numbers
// that overflow a double (1e400).
nlohmann::json parse_json_text(std::string_view text, const std::string& name, bool comments = false);

// Reads and parses a file. Throws npt::Error: "PATH: no such file", "PATH: cannot read", "PATH: file is
// empty", "PATH: not valid JSON: ..." (above).
nlohmann::json read_json_file(const std::filesystem::path& path, bool comments = false);

// The MessagePack counterpart of check_json_depth: walks the encoding without recursion (without allocating
// for the counts it claims) and throws npt::Error naming `name` when maps and arrays nest deeper than
// k_max_json_depth. Truncated or malformed data is left to the parser.
void check_msgpack_depth(const uint8_t* data, size_t size, const std::string& name);

}  // namespace npt
