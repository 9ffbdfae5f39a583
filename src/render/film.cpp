#include "render/film.h"

#include "core/error.h"

namespace npt::render {

AovImages make_aov_images(int width, int height, uint32_t mask) {
    AovImages a;
    if (mask & k_aov_albedo) a.albedo = Image(width, height, 3);
    if (mask & k_aov_normal) a.normal = Image(width, height, 3);
    if (mask & k_aov_depth) a.depth = Image(width, height, 1);
    return a;
}

void AovImages::set(size_t pixel, Rgb albedo_value, Vec3 normal_value, float depth_value) {
    if (!albedo.pixels.empty())
        for (int c = 0; c < 3; ++c) albedo.pixels[3 * pixel + size_t(c)] = albedo_value[c];
    if (!normal.pixels.empty())
        for (int c = 0; c < 3; ++c) normal.pixels[3 * pixel + size_t(c)] = normal_value[c];
    if (!depth.pixels.empty()) depth.pixels[pixel] = depth_value;
}

uint32_t parse_aov_list(const std::string& text) {
    uint32_t mask = 0;
    size_t begin = 0;
    for (;;) {
        const size_t comma = text.find(',', begin);
        const std::string name = text.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin);
        if (name == "albedo")
            mask |= k_aov_albedo;
        else if (name == "normal")
            mask |= k_aov_normal;
        else if (name == "depth")
            mask |= k_aov_depth;
        else
            throw Error("'" + text + "': " + (name.empty() ? std::string("an empty name") : "'" + name + "'") +
                        " is not an AOV (available: albedo, normal, depth, comma-separated)");
        if (comma == std::string::npos) return mask;
        begin = comma + 1;
    }
}

ExrLayerNames aov_exr_names(AovBits aov) {
    switch (aov) {
        case k_aov_albedo:
            return {"albedo", {"R", "G", "B"}};
        case k_aov_normal:
            return {"normal", {"X", "Y", "Z"}};
        case k_aov_depth:
            return {"depth", {"Z"}};
    }
    throw Error("aov_exr_names: not one AOV");
}

}  // namespace npt::render
