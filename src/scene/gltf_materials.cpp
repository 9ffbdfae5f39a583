// glTF materials -> scene::Material, with the KHR extensions we honour, and their textures decoded once per
// (image, colour space): the same image used as base colour (sRGB) and as data (linear) gives two textures.
#include <spdlog/spdlog.h>

#include "core/error.h"
#include "core/image_io.h"
#include "scene/gltf_internal.h"
#include "scene/texture_utils.h"

namespace npt::scene::gltf {
namespace {

double number(const tinygltf::Value& obj, const char* key, double fallback) {
    if (!obj.IsObject() || !obj.Has(key)) return fallback;
    const auto& v = obj.Get(key);
    return v.IsNumber() ? v.GetNumberAsDouble() : fallback;
}

const tinygltf::Value* extension(const tinygltf::Material& m, const char* name) {
    auto it = m.extensions.find(name);
    return it == m.extensions.end() ? nullptr : &it->second;
}

Rgb rgb(const std::vector<double>& v, Rgb fallback) {
    return v.size() >= 3 ? Rgb(float(v[0]), float(v[1]), float(v[2])) : fallback;
}

}  // namespace

MaterialTable::MaterialTable(const Context& ctx, Scene& scene) : m_ctx(ctx), m_scene(scene) {
    // Reserve one slot per glTF material so that indices are a fixed offset; filled below on first use.
    m_offset = int(scene.materials.size());
    scene.materials.resize(scene.materials.size() + ctx.model.materials.size());
    for (size_t i = 0; i < ctx.model.materials.size(); ++i) {
        const auto& gm = ctx.model.materials[i];
        Material& mat = scene.materials[size_t(m_offset) + i];
        const std::string mname = gm.name.empty() ? fmt::format("#{}", i) : gm.name;
        mat.name = mname;
        const auto& pbr = gm.pbrMetallicRoughness;
        mat.base_color = rgb(pbr.baseColorFactor, Rgb(1.0f));
        mat.metallic = float(pbr.metallicFactor);
        mat.roughness = float(pbr.roughnessFactor);
        mat.emission = rgb(gm.emissiveFactor, Rgb(0.0f));
        if (auto* e = extension(gm, "KHR_materials_emissive_strength"))
            mat.emission *= float(number(*e, "emissiveStrength", 1.0));
        if (auto* e = extension(gm, "KHR_materials_specular")) {
            mat.specular = float(number(*e, "specularFactor", 1.0));
            if (e->Has("specularColorFactor") && e->Get("specularColorFactor").IsArray() &&
                e->Get("specularColorFactor").ArrayLen() >= 3) {
                const auto& c = e->Get("specularColorFactor");
                for (int k = 0; k < 3; ++k)
                    mat.specular_color[k] = c.Get(k).IsNumber() ? float(c.Get(k).GetNumberAsDouble()) : 1.0f;
            }
            if (e->Has("specularTexture") || e->Has("specularColorTexture"))
                spdlog::warn("{}: material '{}': specular textures are ignored", ctx.file, mname);
        }
        if (auto* e = extension(gm, "KHR_materials_transmission")) {
            mat.transmission = float(number(*e, "transmissionFactor", 0.0));
            if (e->Has("transmissionTexture"))
                spdlog::warn("{}: material '{}': transmissionTexture is ignored", ctx.file, mname);
        }
        if (auto* e = extension(gm, "KHR_materials_ior")) mat.ior = float(number(*e, "ior", 1.5));
        mat.double_sided = gm.doubleSided;
        mat.is_volume = gm.name == "volume";
        if (!is_finite(mat.base_color) || !is_finite(mat.emission) || !std::isfinite(mat.metallic) ||
            !std::isfinite(mat.roughness) || !std::isfinite(mat.ior) || !std::isfinite(mat.transmission))
            throw Error(ctx.file + ": material '" + mname + "': a factor is not finite");

        mat.base_color_texture = texture(pbr.baseColorTexture.index, true, mname, "baseColorTexture");
        mat.metallic_roughness_texture =
            texture(pbr.metallicRoughnessTexture.index, false, mname, "metallicRoughnessTexture");
        mat.normal_texture = texture(gm.normalTexture.index, false, mname, "normalTexture");
        mat.normal_scale = float(gm.normalTexture.scale);
        mat.emissive_texture = texture(gm.emissiveTexture.index, true, mname, "emissiveTexture");
        for (const auto* info : {&pbr.baseColorTexture, &pbr.metallicRoughnessTexture, &gm.emissiveTexture})
            if (info->index >= 0 && info->texCoord != 0)
                spdlog::warn("{}: material '{}': texCoord {} is not supported, TEXCOORD_0 is used", ctx.file,
                             mname, info->texCoord);
    }
}

int MaterialTable::material(int gltf_index) {
    if (gltf_index >= 0) {
        if (size_t(gltf_index) >= m_ctx.model.materials.size())
            throw Error(m_ctx.file + ": material " + std::to_string(gltf_index) + " does not exist");
        return m_offset + gltf_index;
    }
    if (m_default < 0) {
        // glTF's default material: white, fully metallic, fully rough (glTF 2.0 spec, section 3.9.6).
        Material mat;
        mat.name = "default";
        m_default = int(m_scene.materials.size());
        m_scene.materials.push_back(mat);
    }
    return m_default;
}

int MaterialTable::texture(int gltf_texture, bool srgb, const std::string& material, const char* slot) {
    if (gltf_texture < 0) return -1;
    const auto& model = m_ctx.model;
    const std::string where = m_ctx.file + ": material '" + material + "' " + slot;
    if (size_t(gltf_texture) >= model.textures.size())
        throw Error(where + ": texture " + std::to_string(gltf_texture) + " does not exist");
    const int source = model.textures[size_t(gltf_texture)].source;
    if (source < 0 || size_t(source) >= model.images.size())
        throw Error(where + ": texture " + std::to_string(gltf_texture) + " has no image source");
    auto key = std::make_pair(source, srgb);
    if (auto it = m_textures.find(key); it != m_textures.end()) return it->second;

    const auto& img = model.images[size_t(source)];
    const std::string iname =
        "image " + std::to_string(source) +
        (img.uri.empty() || img.uri.rfind("data:", 0) == 0 ? std::string() : " ('" + img.uri + "')");
    // Our tinygltf image callback keeps the encoded bytes; empty means the file could not be read.
    if (img.image.empty()) {
        const auto dir = std::filesystem::path(m_ctx.file).parent_path();
        throw Error(where + ": " + iname + " not found (looked for " + (dir / img.uri).string() + ")");
    }
    const std::string label = img.uri.empty() || img.uri.rfind("data:", 0) == 0
                                  ? "<embedded #" + std::to_string(source) + ">"
                                  : (std::filesystem::path(m_ctx.file).parent_path() / img.uri).string();
    Image decoded;
    try {
        decoded = decode_image(img.image.data(), img.image.size(), label, srgb);
    } catch (const Error& e) {
        throw Error(where + ": " + iname + ": " + e.what());
    }
    m_scene.textures.push_back(make_texture(decoded, label));
    const int idx = int(m_scene.textures.size()) - 1;
    m_textures[key] = idx;
    return idx;
}

}  // namespace npt::scene::gltf
