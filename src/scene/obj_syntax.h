// A strict pass over OBJ and MTL text before tinyobjloader reads it. tinyobjloader is lenient where we must
// not be: a number it cannot parse ("nan", "inf", "1e999", "1,5") silently becomes 0, a face index is read
// with atoi (undefined beyond 32 bits) and never range-checked, and a corner's texture-coordinate index is
// dropped when another corner has none. Every statement we use is checked here, with the line number.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace npt::scene {

// Throws npt::Error "FILE: line N: ..." when a `v`, `vn` or `vt` statement has a missing, malformed or
// non-finite number, or an `f`, `l` or `p` statement has an index that is malformed, 0, beyond 32 bits, or
// refers to an element that does not exist (positive: among all of the file's elements; negative: among
// those before it). Returns the file names of its `mtllib` statements.
std::vector<std::string> check_obj_text(std::string_view text, const std::string& file);

// Throws npt::Error "FILE: line N: KEY: ..." when a numeric MTL statement we read (Ka, Kd, Ks, Ke, Kt, Tf,
// Ns, Ni, d, Tr, illum) has a malformed or non-finite number.
void check_mtl_text(std::string_view text, const std::string& file);

}  // namespace npt::scene
