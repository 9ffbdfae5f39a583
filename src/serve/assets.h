// The page's files embedded in the binary at build time (web/ and the npm packages three and lil-gui, with
// their licences): src/serve/CMakeLists.txt generates their table.
#pragma once

#include <cstddef>
#include <string_view>

namespace npt::serve {

struct Asset {
    std::string_view path;          // URL path, "/index.html"
    std::string_view content_type;  // "text/html; charset=utf-8"
    const unsigned char* data;
    size_t size;
};

// The asset at a URL path ("/" is "/index.html"), or null.
const Asset* find_asset(std::string_view path);

// False when the build could not fetch three.js and lil-gui from npm: the page then says so.
bool vendor_assets_present();

}  // namespace npt::serve
