// instant-ngp snapshots (.msgpack, gzip/zlib .ingp; nerf/ngp_snapshot.h), from memory.
#include <vector>

#include "harness_support.h"
#include "nerf/ngp_snapshot.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace npt;
    (void)fuzz::scratch();  // logging off
    const std::vector<uint8_t> bytes(data, data + size);
    fuzz::refuse_or_load([&] { nerf::import_ngp_snapshot(bytes, "in.msgpack"); });
    return 0;
}
