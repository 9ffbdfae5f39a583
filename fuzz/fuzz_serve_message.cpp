// nerfpt serve's message parser (serve/protocol.h): what a page sends over the WebSocket.
#include <string_view>

#include "harness_support.h"
#include "serve/protocol.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    npt::fuzz::refuse_or_load(
        [&] { npt::serve::parse_client_message(std::string_view(reinterpret_cast<const char*>(data), size)); });
    return 0;
}
