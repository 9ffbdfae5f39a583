// Volume grids (media/volume_grid.h). First byte: 0 OpenVDB (.vdb), 1 NanoVDB (.nvdb), else an instant-ngp
// raw grid whose size W, H, D (1..255) are the next three bytes; the rest is the file.
#include <string>

#include "harness_support.h"
#include "media/volume_grid.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace npt;
    if (size < 1) return 0;
    std::string name;
    size_t skip = 1;
    if (data[0] == 0) {
        name = "in.vdb";
    } else if (data[0] == 1) {
        name = "in.nvdb";
    } else {
        if (size < 4) return 0;
        name = std::to_string(int(data[1])) + "x" + std::to_string(int(data[2])) + "x" +
               std::to_string(int(data[3])) + "_in.bin";
        skip = 4;
    }
    const auto path = fuzz::put(name, data + skip, size - skip);
    media::GridLoadOptions options;
    // A few bytes may ask for the full 2^28-voxel dense grid (a 4096^3 tile): legitimate, and ~30 s of
    // filling under ASan, past libFuzzer's timeout. Parsing is what is fuzzed; the limit's check still runs.
    // 2^20: a colour grid on other voxels than the density is resampled voxel by voxel through OpenVDB's
    // accessor, 0.16 s for 1.5 M voxels in a release build but 27 s under ASan and coverage (the 1 M campaign).
    options.max_voxels = size_t(1) << 20;
    fuzz::refuse_or_load([&] { media::load_volume_grid(path, options); });
    std::filesystem::remove(path);
    return 0;
}
