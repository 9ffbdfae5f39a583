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

float clamp_field(const Context& ctx, float value, float lo, float hi, const std::string& field,
                  const std::string& owner) {
    if (value >= lo && value <= hi) return value;
    const float clamped = value < lo ? lo : hi;
    if (ctx.clamped.insert(field).second)
        spdlog::warn(
            "{}: {}: {} {} is outside [{}, {}], clamped to {} (further clamps of {} in this file are "
            "not reported)",
            ctx.file, owner, field, value, lo, hi, clamped, field);
    return clamped;
}

Rgb clamp_field(const Context& ctx, Rgb value, float lo, float hi, const std::string& field,
                const std::string& owner) {
    for (int k = 0; k < 3; ++k) value[k] = clamp_field(ctx, value[k], lo, hi, field, owner);
    return value;
}

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
        // Factors the spec bounds are clamped as Blender does, one warning per field (types and the other
        // ranges were checked by check_schema); docs/formats.md, "glTF 2.0", lists the rule per field.
        const std::string owner = "material '" + mname + "'";
        const auto unit = [&](double v, const char* field) {
            return clamp_field(ctx, float(v), 0.0f, 1.0f, field, owner);
        };
        mat.base_color = clamp_field(ctx, rgb(pbr.baseColorFactor, Rgb(1.0f)), 0.0f, 1.0f,
                                     "pbrMetallicRoughness.baseColorFactor", owner);
        mat.metallic = unit(pbr.metallicFactor, "pbrMetallicRoughness.metallicFactor");
        mat.roughness = unit(pbr.roughnessFactor, "pbrMetallicRoughness.roughnessFactor");
        mat.emission =
            clamp_field(ctx, rgb(gm.emissiveFactor, Rgb(0.0f)), 0.0f, 1.0f, "emissiveFactor", owner);
        if (auto* e = extension(gm, "KHR_materials_emissive_strength"))
            mat.emission *= float(number(*e, "emissiveStrength", 1.0));
        if (auto* e = extension(gm, "KHR_materials_specular")) {
            mat.specular = unit(number(*e, "specularFactor", 1.0), "KHR_materials_specular.specularFactor");
            if (e->Has("specularColorFactor") && e->Get("specularColorFactor").IsArray() &&
                e->Get("specularColorFactor").ArrayLen() >= 3) {
                const auto& c = e->Get("specularColorFactor");
                for (int k = 0; k < 3; ++k)
                    mat.specular_color[k] = c.Get(k).IsNumber() ? float(c.Get(k).GetNumberAsDouble()) : 1.0f;
                mat.specular_color = clamp_field(ctx, mat.specular_color, 0.0f, INFINITY,
                                                 "KHR_materials_specular.specularColorFactor", owner);
            }
            if (e->Has("specularTexture") || e->Has("specularColorTexture"))
                spdlog::warn("{}: material '{}': specular textures are ignored", ctx.file, mname);
        }
        if (auto* e = extension(gm, "KHR_materials_transmission")) {
            mat.transmission =
                unit(number(*e, "transmissionFactor", 0.0), "KHR_materials_transmission.transmissionFactor");
            if (e->Has("transmissionTexture"))
                spdlog::warn("{}: material '{}': transmissionTexture is ignored", ctx.file, mname);
        }
        if (auto* e = extension(gm, "KHR_materials_ior")) mat.ior = float(number(*e, "ior", 1.5));
        mat.double_sided = gm.doubleSided;
        mat.is_volume = gm.name == "volume";
        // Values beyond float (1e300 is a valid JSON number) end up here.
        if (!is_finite(mat.base_color) || !is_finite(mat.emission) || !std::isfinite(mat.metallic) ||
            !std::isfinite(mat.roughness) || !std::isfinite(mat.ior) || !std::isfinite(mat.transmission) ||
            !std::isfinite(mat.specular) || !is_finite(mat.specular_color))
            throw Error(ctx.file + ": material '" + mname + "': a factor is not finite as a float");

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
