// COLMAP binary models (capture/colmap_model.h). Input: u32 length of cameras.bin, u32 length of images.bin
// (little endian), then cameras.bin, images.bin and points3D.bin (the rest).
#include <cstring>

#include "capture/colmap_model.h"
#include "harness_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace npt;
    if (size < 8) return 0;
    uint32_t n_cameras = 0, n_images = 0;
    std::memcpy(&n_cameras, data, 4);
    std::memcpy(&n_images, data + 4, 4);
    const size_t rest = size - 8;
    if (n_cameras > rest || n_images > rest - n_cameras) return 0;
    std::filesystem::create_directories(fuzz::scratch() / "sparse");
    fuzz::put("sparse/cameras.bin", data + 8, n_cameras);
    fuzz::put("sparse/images.bin", data + 8 + n_cameras, n_images);
    fuzz::put("sparse/points3D.bin", data + 8 + n_cameras + n_images, rest - n_cameras - n_images);
    fuzz::refuse_or_load([&] { capture::read_colmap_model(fuzz::scratch() / "sparse"); });
    return 0;
}
