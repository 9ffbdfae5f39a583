// Builds small glTF documents in memory (one binary buffer, embedded as base64 or as a GLB chunk), so that every
// loader test states exactly what its file holds.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "test_support.h"

namespace npt::test {

inline std::string base64(const std::string& in) {
    static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    size_t i = 0;
    for (; i + 2 < in.size(); i += 3) {
        uint32_t v = uint32_t(uint8_t(in[i])) << 16 | uint32_t(uint8_t(in[i + 1])) << 8 | uint8_t(in[i + 2]);
        for (int s = 18; s >= 0; s -= 6) out += k[(v >> s) & 63];
    }
    if (i + 1 == in.size()) {
        uint32_t v = uint32_t(uint8_t(in[i])) << 16;
        out += k[(v >> 18) & 63];
        out += k[(v >> 12) & 63];
        out += "==";
    } else if (i + 2 == in.size()) {
        uint32_t v = uint32_t(uint8_t(in[i])) << 16 | uint32_t(uint8_t(in[i + 1])) << 8;
        out += k[(v >> 18) & 63];
        out += k[(v >> 12) & 63];
        out += k[(v >> 6) & 63];
        out += '=';
    }
    return out;
}

// Builds a glTF document with one binary buffer, in memory, so every test states exactly what the file holds.
struct Builder {
    using json = nlohmann::json;
    json j = {
        {"asset", {{"version", "2.0"}}}, {"scene", 0}, {"scenes", json::array({{{"nodes", json::array()}}})}};
    std::string bin;

    int view(const void* data, size_t bytes) {
        while (bin.size() % 4) bin += '\0';
        const size_t offset = bin.size();
        bin.append(static_cast<const char*>(data), bytes);
        j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}});
        return int(j["bufferViews"].size()) - 1;
    }
    int accessor(int view, int ctype, size_t count, const char* type) {
        j["accessors"].push_back(
            {{"bufferView", view}, {"componentType", ctype}, {"count", count}, {"type", type}});
        return int(j["accessors"].size()) - 1;
    }
    int vec3(const std::vector<float>& v) {
        return accessor(view(v.data(), v.size() * 4), 5126, v.size() / 3, "VEC3");
    }
    // FLOAT accessor of `type` ("SCALAR", "VEC3", "VEC4"): animation inputs and outputs.
    int floats(const std::vector<float>& v, const char* type) {
        const size_t width = std::string(type) == "SCALAR" ? 1 : std::string(type) == "VEC3" ? 3 : 4;
        return accessor(view(v.data(), v.size() * 4), 5126, v.size() / width, type);
    }
    int vec2(const std::vector<float>& v) {
        return accessor(view(v.data(), v.size() * 4), 5126, v.size() / 2, "VEC2");
    }
    int indices32(const std::vector<uint32_t>& v) {
        return accessor(view(v.data(), v.size() * 4), 5125, v.size(), "SCALAR");
    }
    int indices16(const std::vector<uint16_t>& v) {
        return accessor(view(v.data(), v.size() * 2), 5123, v.size(), "SCALAR");
    }
    int indices8(const std::vector<uint8_t>& v) {
        return accessor(view(v.data(), v.size()), 5121, v.size(), "SCALAR");
    }
    int mesh(json attributes, int indices = -1, int material = -1, const std::string& name = "m") {
        json prim = {{"attributes", attributes}};
        if (indices >= 0) prim["indices"] = indices;
        if (material >= 0) prim["material"] = material;
        j["meshes"].push_back({{"name", name}, {"primitives", json::array({prim})}});
        return int(j["meshes"].size()) - 1;
    }
    // One triangle in the z = 0 plane, counter-clockwise seen from +z.
    int triangle(int material = -1, const std::string& name = "tri") {
        int p = vec3({0, 0, 0, 1, 0, 0, 0, 1, 0});
        return mesh({{"POSITION", p}}, indices32({0, 1, 2}), material, name);
    }
    int node(json n, bool root = true) {
        j["nodes"].push_back(n);
        int i = int(j["nodes"].size()) - 1;
        if (root) j["scenes"][0]["nodes"].push_back(i);
        return i;
    }
    std::string gltf() {
        json d = j;
        if (!bin.empty())
            d["buffers"] = json::array({{{"byteLength", bin.size()},
                                         {"uri", "data:application/octet-stream;base64," + base64(bin)}}});
        return d.dump();
    }
    std::filesystem::path write(const std::string& name = "scene.gltf") {
        std::filesystem::path p = test::temp_dir() / name;
        test::write_file(p, gltf());
        return p;
    }
    std::string glb() {
        json d = j;
        d["buffers"] = json::array({{{"byteLength", bin.size()}}});
        std::string js = d.dump(), b = bin;
        while (js.size() % 4) js += ' ';
        while (b.size() % 4) b += '\0';
        auto u32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
        return "glTF" + u32(2) + u32(uint32_t(12 + 8 + js.size() + 8 + b.size())) + u32(uint32_t(js.size())) +
               u32(0x4E4F534A) + js + u32(uint32_t(b.size())) + u32(0x004E4942) + b;
    }
};

}  // namespace npt::test
