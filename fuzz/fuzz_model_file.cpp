// The nerfpt model file (.npt, nerf/model_file.h). Most mutations fail the checksum; the harness also
// re-seals the input with a correct checksum (when it ends in a CKSM section) so that the sections behind it
// are fuzzed too.
#include <cstring>
#include <vector>

#include "harness_support.h"
#include "nerf/model_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace npt;
    const auto path = fuzz::put("in.npt", data, size);
    fuzz::refuse_or_load([&] { nerf::load_model(path); });
    if (size >= 20 && std::memcmp(data + size - 20, "CKSM", 4) == 0) {
        std::vector<uint8_t> sealed(data, data + size);
        const uint64_t h = nerf::model_file_hash(sealed.data(), size - 20);
        std::memcpy(sealed.data() + size - 8, &h, 8);
        const auto resealed = fuzz::put("sealed.npt", sealed.data(), sealed.size());
        fuzz::refuse_or_load([&] { nerf::load_model(resealed); });
    }
    return 0;
}
