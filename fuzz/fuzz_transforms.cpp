// NeRF data sets: transforms.json (nerf/dataset.h). The scratch folder holds a.png and b.png (4x3) for
// frames.
#include "core/image.h"
#include "core/image_io.h"
#include "harness_support.h"
#include "nerf/dataset.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace npt;
    static const bool images = [] {
        Image img(4, 3, 4);
        for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = float(i % 7) / 6.0f;
        write_png(fuzz::scratch() / "a.png", img);
        write_png(fuzz::scratch() / "b.png", img);
        return true;
    }();
    (void)images;
    const auto path = fuzz::put("transforms.json", data, size);
    fuzz::refuse_or_load([&] { nerf::load_dataset(path, ""); });
    return 0;
}
