#include "nerf/relight/relight_section.h"

#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "core/error.h"

namespace npt::nerf {

namespace {

using nlohmann::json;
constexpr int k_section_version = 1;

void append(std::vector<uint8_t>& out, const void* data, size_t n) {
    const auto* p = static_cast<const uint8_t*>(data);
    out.insert(out.end(), p, p + n);
}

int get_int(const json& j, const char* key, int lo, int hi, const std::string& where) {
    if (!j.contains(key) || !j[key].is_number_integer())
        throw Error(where + ": field '" + key + "' is missing or not an integer");
    const int64_t v = j[key].get<int64_t>();
    if (v < lo || v > hi)
        throw Error(where + ": field '" + key + "' is " + std::to_string(v) + ", outside [" + std::to_string(lo) +
                    ", " + std::to_string(hi) + "]");
    return int(v);
}

double get_number(const json& j, const char* key, double lo, double hi, const std::string& where) {
    if (!j.contains(key) || !j[key].is_number())
        throw Error(where + ": field '" + key + "' is missing or not a number");
    const double v = j[key].get<double>();
    if (!std::isfinite(v) || v < lo || v > hi)
        throw Error(where + ": field '" + key + "' is out of range");
    return v;
}

}  // namespace

std::vector<uint8_t> encode_relight_section(const RelightFields& f, float aabb_scale) {
    const IntrinsicLayout layout = make_intrinsic_layout(f.config, aabb_scale);
    if (f.params.size() != layout.total)
        throw Error("relight section: " + std::to_string(f.params.size()) + " parameters, the config needs " +
                    std::to_string(layout.total));
    if (f.capture_env.texels.size() != size_t(f.capture_env.width) * size_t(f.capture_env.height))
        throw Error("relight section: the environment's texel count does not match its size");
    const json header = {
        {"version", k_section_version},
        {"intrinsic",
         {{"levels", f.config.grid.levels},
          {"features_per_level", f.config.grid.features_per_level},
          {"log2_table_size", f.config.grid.log2_table_size},
          {"base_resolution", f.config.grid.base_resolution},
          {"finest_resolution", f.config.finest_resolution},
          {"width", f.config.width},
          {"hidden_layers", f.config.hidden_layers},
          {"diffuse", f.config.diffuse == IntrinsicDiffuse::burley ? "burley" : "layered"}}},
        {"parameters", f.params.size()},
        {"environment", {f.capture_env.width, f.capture_env.height}},
        {"exposures", f.exposure.size()},
        {"steps", f.steps},
        {"seconds", f.seconds}};
    const std::string text = header.dump();
    std::vector<uint8_t> out;
    const uint64_t len = text.size();
    append(out, &len, 8);
    append(out, text.data(), text.size());
    append(out, f.params.data(), f.params.size() * 4);
    append(out, f.capture_env.texels.data(), f.capture_env.texels.size() * sizeof(Rgb));
    append(out, f.exposure.data(), f.exposure.size() * sizeof(Rgb));
    return out;
}

RelightFields decode_relight_section(const uint8_t* data, size_t size, const std::string& source,
                                     float aabb_scale) {
    static_assert(sizeof(Rgb) == 12, "Rgb is stored as three float32");
    const std::string where = source + ": relight section";
    if (size < 8) throw Error(where + ": truncated (" + std::to_string(size) + " bytes)");
    uint64_t len;
    std::memcpy(&len, data, 8);
    if (len > size - 8) throw Error(where + ": header length " + std::to_string(len) + " past the section's end");
    json h;
    try {
        h = json::parse(std::string(reinterpret_cast<const char*>(data + 8), size_t(len)));
    } catch (const json::exception&) {
        throw Error(where + ": the header is not valid JSON");
    }
    if (!h.is_object()) throw Error(where + ": the header is not a JSON object");
    const int version = get_int(h, "version", 0, 1 << 20, where);
    if (version != k_section_version)
        throw Error(where + ": version " + std::to_string(version) + " (this build reads " +
                    std::to_string(k_section_version) + ")");
    if (!h.contains("intrinsic") || !h["intrinsic"].is_object())
        throw Error(where + ": field 'intrinsic' is missing or not an object");
    const json& ic = h["intrinsic"];
    RelightFields f;
    const std::string iw = where + " 'intrinsic'";
    f.config.grid.levels = get_int(ic, "levels", 1, k_max_hash_levels, iw);
    f.config.grid.features_per_level = get_int(ic, "features_per_level", 1, 8, iw);
    f.config.grid.log2_table_size = get_int(ic, "log2_table_size", 4, 24, iw);
    f.config.grid.base_resolution = get_int(ic, "base_resolution", 1, 1 << 12, iw);
    f.config.finest_resolution = float(get_number(ic, "finest_resolution", 1.0, 1 << 16, iw));
    f.config.width = get_int(ic, "width", 1, k_max_mlp_width, iw);
    f.config.hidden_layers = get_int(ic, "hidden_layers", 1, 8, iw);
    f.config.diffuse = IntrinsicDiffuse::layered;  // the first relightable models do not say
    if (ic.contains("diffuse")) {
        const json& d = ic["diffuse"];
        if (!d.is_string() || (d != "burley" && d != "layered"))
            throw Error(iw + ": field 'diffuse' must be \"burley\" or \"layered\"");
        f.config.diffuse = d == "burley" ? IntrinsicDiffuse::burley : IntrinsicDiffuse::layered;
    }
    if (f.config.grid.levels * f.config.grid.features_per_level > k_max_mlp_width)
        throw Error(iw + ": levels x features_per_level exceeds " + std::to_string(k_max_mlp_width));
    if (!h.contains("environment") || !h["environment"].is_array() || h["environment"].size() != 2)
        throw Error(where + ": field 'environment' must be [width, height]");
    const json env_size = {{"width", h["environment"][0]}, {"height", h["environment"][1]}};
    // 0 x 0: no capture light was estimated (a model made without the relight stage's fit).
    f.capture_env.width = get_int(env_size, "width", 0, 4096, where + " 'environment'");
    f.capture_env.height = get_int(env_size, "height", 0, 2048, where + " 'environment'");
    if ((f.capture_env.width == 0) != (f.capture_env.height == 0) || f.capture_env.width == 1)
        throw Error(where + ": field 'environment' is " + std::to_string(f.capture_env.width) + "x" +
                    std::to_string(f.capture_env.height) + " (0x0, or at least 2x1 texels)");
    const int64_t exposures = get_int(h, "exposures", 0, 1 << 24, where);
    f.steps = uint64_t(get_number(h, "steps", 0, 1e15, where));
    f.seconds = get_number(h, "seconds", 0, 1e12, where);

    const IntrinsicLayout layout = make_intrinsic_layout(f.config, aabb_scale);
    const double stated = get_number(h, "parameters", 0, 1e12, where);
    if (stated != double(layout.total))
        throw Error(where + ": 'parameters' is " + std::to_string(uint64_t(stated)) + ", the config needs " +
                    std::to_string(layout.total));
    const size_t n_env = size_t(f.capture_env.width) * size_t(f.capture_env.height);
    const uint64_t need = uint64_t(layout.total) * 4 + uint64_t(n_env) * 12 + uint64_t(exposures) * 12;
    const uint64_t have = size - 8 - len;
    if (need != have)
        throw Error(where + ": the arrays need " + std::to_string(need) + " bytes, the section holds " +
                    std::to_string(have));
    const uint8_t* p = data + 8 + len;
    f.params.resize(layout.total);
    std::memcpy(f.params.data(), p, layout.total * 4);
    p += layout.total * 4;
    f.capture_env.texels.resize(n_env);
    std::memcpy(f.capture_env.texels.data(), p, n_env * 12);
    p += n_env * 12;
    f.exposure.resize(size_t(exposures));
    std::memcpy(f.exposure.data(), p, size_t(exposures) * 12);
    for (size_t i = 0; i < f.params.size(); ++i)
        if (!std::isfinite(f.params[i])) throw Error(where + ": parameter " + std::to_string(i) + " is NaN or Inf");
    auto check_radiance = [&](const std::vector<Rgb>& v, const char* what) {
        for (size_t i = 0; i < v.size(); ++i)
            for (int c = 0; c < 3; ++c)
                if (!std::isfinite(v[i][c]) || v[i][c] < 0.0f)
                    throw Error(where + ": " + what + " " + std::to_string(i) + " is negative, NaN or Inf");
    };
    check_radiance(f.capture_env.texels, "environment texel");
    check_radiance(f.exposure, "exposure");
    return f;
}

}  // namespace npt::nerf
