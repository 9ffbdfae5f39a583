#include "scene/texture_utils.h"

namespace npt::scene {

Texture make_texture(const Image& image, std::string name) {
    Texture t;
    t.name = std::move(name);
    t.width = image.width;
    t.height = image.height;
    const size_t n = size_t(image.width) * size_t(image.height);
    t.rgba.resize(n * 4);
    for (size_t i = 0; i < n; ++i) {
        const float* s = image.pixels.data() + i * size_t(image.channels);
        float* d = t.rgba.data() + i * 4;
        d[0] = s[0];
        d[1] = s[1];
        d[2] = s[2];
        d[3] = image.channels == 4 ? s[3] : 1.0f;
    }
    return t;
}

}  // namespace npt::scene
