// NeRF configs (nerf/nerf_config.h): `nerfpt train --config`, and the copy stored in every model file.
#include "harness_support.h"
#include "nerf/nerf_config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace npt;
    const auto path = fuzz::put("config.json", data, size);
    fuzz::refuse_or_load([&] { nerf::load_config(path.string()); });
    return 0;
}
