// The glTF 2.0 JSON schema (and the KHR extensions we read), checked on the document before tinygltf sees it:
// tinygltf drops a value of the wrong type and keeps the default (`"primitives": 5` loads a mesh with no
// primitives, `"baseColorFactor": "red"` a white material), so types, required fields, index ranges and the
// spec's value ranges are checked here, each error naming the file and the field's JSON path.
#include <fmt/format.h>

#include <cmath>
#include <optional>
#include <string>

#include "core/error.h"
#include "scene/gltf_internal.h"

namespace npt::scene::gltf {
namespace {

using nlohmann::json;

constexpr double k_pi = 3.14159265358979323846;

const char* kind(const json& j) {
    switch (j.type()) {
        case json::value_t::object:
            return "an object";
        case json::value_t::array:
            return "an array";
        case json::value_t::string:
            return "a string";
        case json::value_t::boolean:
            return "a boolean";
        case json::value_t::null:
            return "null";
        case json::value_t::number_integer:
        case json::value_t::number_unsigned:
            return "an integer";
        case json::value_t::number_float:
            return "a number";
        default:
            return "binary data";
    }
}

// 'text' (built by appending: GCC 12 warns falsely on "'" + std::string(...) under -O3, -Wrestrict).
std::string in_quotes(std::string_view s) {
    std::string q;
    q.reserve(s.size() + 2);
    q += '\'';
    q += s;
    q += '\'';
    return q;
}

// Whole numbers without a fraction ("3", not "3.0"): messages quote the file's values.
std::string number_text(double v) {
    if (v == std::floor(v) && std::abs(v) < 1e15) return std::to_string(static_cast<long long>(v));
    return json(v).dump();
}

// A number range: [lo, hi], either end open. Infinite ends are no bound.
struct Range {
    double lo = -INFINITY, hi = INFINITY;
    bool lo_open = false, hi_open = false;
    bool contains(double v) const { return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi); }
    std::string text() const {
        if (std::isinf(hi)) return std::string(lo_open ? "> " : ">= ") + number_text(lo);
        if (std::isinf(lo)) return std::string(hi_open ? "< " : "<= ") + number_text(hi);
        return std::string(lo_open ? "(" : "[") + number_text(lo) + ", " + number_text(hi) +
               (hi_open ? ")" : "]");
    }
};
constexpr Range k_any{};
constexpr Range k_non_negative{0.0, INFINITY, false, false};
constexpr Range k_positive{0.0, INFINITY, true, false};

class Checker {
  public:
    Checker(const json& doc, const std::string& file) : m_doc(doc), m_file(file) {}

    void run() {
        if (!m_doc.is_object()) fail("(top level)", std::string("expected an object, got ") + kind(m_doc));
        const std::string root;
        if (const json* a = opt(m_doc, "asset", root, json::value_t::object)) string(*a, "version", "asset");
        integer_id(m_doc, "scene", root, "scenes");
        strings(m_doc, "extensionsUsed", root);
        strings(m_doc, "extensionsRequired", root);
        each(m_doc, "scenes", root, [&](const json& s, const std::string& p) {
            string(s, "name", p);
            ids(s, "nodes", p, "nodes");
        });
        each(m_doc, "nodes", root, [&](const json& n, const std::string& p) { node(n, p); });
        each(m_doc, "meshes", root, [&](const json& m, const std::string& p) { mesh(m, p); });
        each(m_doc, "accessors", root, [&](const json& a, const std::string& p) { accessor(a, p); });
        each(m_doc, "bufferViews", root, [&](const json& v, const std::string& p) { buffer_view(v, p); });
        each(m_doc, "buffers", root, [&](const json& b, const std::string& p) {
            string(b, "uri", p);
            required(b, "byteLength", p);
            integer(b, "byteLength", p, 1, 1e18);
        });
        each(m_doc, "images", root, [&](const json& i, const std::string& p) {
            string(i, "uri", p);
            string(i, "mimeType", p);
            integer_id(i, "bufferView", p, "bufferViews");
        });
        each(m_doc, "textures", root, [&](const json& t, const std::string& p) {
            integer_id(t, "sampler", p, "samplers");
            integer_id(t, "source", p, "images");
        });
        each(m_doc, "samplers", root, [&](const json& s, const std::string& p) {
            for (const char* k : {"magFilter", "minFilter", "wrapS", "wrapT"}) integer(s, k, p, 0, 65535);
        });
        each(m_doc, "materials", root, [&](const json& m, const std::string& p) { material(m, p); });
        each(m_doc, "cameras", root, [&](const json& c, const std::string& p) { camera(c, p); });
        if (const json* ext = opt(m_doc, "extensions", root, json::value_t::object))
            if (const json* lp = opt(*ext, "KHR_lights_punctual", "extensions", json::value_t::object))
                each(*lp, "lights", "extensions.KHR_lights_punctual",
                     [&](const json& l, const std::string& p) { light(l, p); });
    }

  private:
    [[noreturn]] void fail(const std::string& path, const std::string& what) const {
        throw Error(m_file + ": " + path + ": " + what);
    }
    static std::string join(const std::string& path, const char* key) {
        return path.empty() ? std::string(key) : path + "." + key;
    }

    // The value at obj[key] if present; of `type` (integers count as numbers), else an error.
    const json* opt(const json& obj, const char* key, const std::string& path, json::value_t type) const {
        auto it = obj.find(key);
        if (it == obj.end()) return nullptr;
        const bool ok = type == json::value_t::number_float ? it->is_number() : it->type() == type;
        if (!ok) fail(join(path, key), std::string("expected ") + kind(json(type)) + ", got " + kind(*it));
        return &*it;
    }
    void required(const json& obj, const char* key, const std::string& path) const {
        if (!obj.contains(key)) fail(join(path, key), "missing (required by glTF 2.0)");
    }
    void string(const json& obj, const char* key, const std::string& path) const {
        opt(obj, key, path, json::value_t::string);
    }
    void boolean(const json& obj, const char* key, const std::string& path) const {
        opt(obj, key, path, json::value_t::boolean);
    }
    void one_of(const json& obj, const char* key, const std::string& path,
                std::initializer_list<const char*> allowed) const {
        const json* v = opt(obj, key, path, json::value_t::string);
        if (!v) return;
        std::string list;
        for (const char* a : allowed) {
            if (*v == a) return;
            list += (list.empty() ? "" : ", ") + std::string(a);
        }
        fail(join(path, key), in_quotes(v->get<std::string>()) + " is not one of " + list);
    }
    std::optional<double> number(const json& obj, const char* key, const std::string& path,
                                 Range range = k_any) const {
        const json* v = opt(obj, key, path, json::value_t::number_float);
        if (!v) return std::nullopt;
        const double d = v->get<double>();
        if (!std::isfinite(d)) fail(join(path, key), "is not finite");
        if (!range.contains(d))
            fail(join(path, key), number_text(d) + " is out of range: must be " + range.text());
        return d;
    }
    bool is_integer(const json& v) const {
        if (v.is_number_integer()) return true;
        return v.is_number_float() && std::isfinite(v.get<double>()) &&
               v.get<double>() == std::floor(v.get<double>());
    }
    std::optional<double> integer(const json& obj, const char* key, const std::string& path, double lo,
                                  double hi) const {
        auto it = obj.find(key);
        if (it == obj.end()) return std::nullopt;
        if (!is_integer(*it)) fail(join(path, key), std::string("expected an integer, got ") + kind(*it));
        const double d = it->get<double>();
        if (d < lo || d > hi)
            fail(join(path, key), number_text(d) + " is out of range: must be in [" + number_text(lo) + ", " +
                                      number_text(hi) + "]");
        return d;
    }
    size_t count(const char* array) const {
        auto it = m_doc.find(array);
        return it != m_doc.end() && it->is_array() ? it->size() : 0;
    }
    // An index into the document's array `array`, which has `n` elements.
    void check_id(const json& v, const std::string& path, const char* array, size_t n) const {
        if (!is_integer(v) || v.get<double>() < 0)
            fail(path, std::string("expected an index into '") + array + "' (an integer >= 0), got " +
                           (v.is_number() ? number_text(v.get<double>()) : kind(v)));
        const double d = v.get<double>();
        if (d >= double(n))
            fail(path, number_text(d) + " does not exist ('" + array + "' has " + std::to_string(n) +
                           (n == 1 ? " element)" : " elements)"));
    }
    void check_id(const json& v, const std::string& path, const char* array) const {
        check_id(v, path, array, count(array));
    }
    void integer_id(const json& obj, const char* key, const std::string& path, const char* array) const {
        auto it = obj.find(key);
        if (it != obj.end()) check_id(*it, join(path, key), array);
    }
    void ids(const json& obj, const char* key, const std::string& path, const char* array) const {
        const json* a = opt(obj, key, path, json::value_t::array);
        if (!a) return;
        for (size_t i = 0; i < a->size(); ++i)
            check_id((*a)[i], join(path, key) + "[" + std::to_string(i) + "]", array);
    }
    void strings(const json& obj, const char* key, const std::string& path) const {
        const json* a = opt(obj, key, path, json::value_t::array);
        if (!a) return;
        for (size_t i = 0; i < a->size(); ++i)
            if (!(*a)[i].is_string())
                fail(join(path, key) + "[" + std::to_string(i) + "]",
                     std::string("expected a string, got ") + kind((*a)[i]));
    }
    // An array of exactly n (or, with n == 0, any number of) finite numbers.
    const json* numbers(const json& obj, const char* key, const std::string& path, size_t n) const {
        auto it = obj.find(key);
        if (it == obj.end()) return nullptr;
        const std::string expect = n ? fmt::format("expected an array of {} numbers", n)
                                     : std::string("expected an array of numbers");
        if (!it->is_array()) fail(join(path, key), expect + ", got " + kind(*it));
        if (n && it->size() != n)
            fail(join(path, key), expect + ", got " + std::to_string(it->size()) + " elements");
        for (size_t i = 0; i < it->size(); ++i)
            if (!(*it)[i].is_number() || !std::isfinite((*it)[i].get<double>()))
                fail(join(path, key) + "[" + std::to_string(i) + "]",
                     std::string("expected a number, got ") + kind((*it)[i]));
        return &*it;
    }
    template <typename Fn>
    void each(const json& obj, const char* key, const std::string& path, Fn&& fn) const {
        const json* a = opt(obj, key, path, json::value_t::array);
        if (!a) return;
        for (size_t i = 0; i < a->size(); ++i) {
            const std::string p = join(path, key) + "[" + std::to_string(i) + "]";
            if (!(*a)[i].is_object()) fail(p, std::string("expected an object, got ") + kind((*a)[i]));
            fn((*a)[i], p);
        }
    }

    void node(const json& n, const std::string& p) const {
        string(n, "name", p);
        integer_id(n, "camera", p, "cameras");
        integer_id(n, "mesh", p, "meshes");
        integer_id(n, "skin", p, "skins");
        ids(n, "children", p, "nodes");
        numbers(n, "matrix", p, 16);
        numbers(n, "translation", p, 3);
        numbers(n, "scale", p, 3);
        numbers(n, "weights", p, 0);
        if (const json* q = numbers(n, "rotation", p, 4)) {
            double norm2 = 0;
            for (const json& c : *q) norm2 += c.get<double>() * c.get<double>();
            // A zero quaternion has no rotation to normalise to (a non-unit one is normalised, as Blender
            // does).
            if (!(norm2 > 1e-12))
                fail(join(p, "rotation"), "the quaternion [x, y, z, w] is zero: no rotation");
        }
        if (const json* ext = opt(n, "extensions", p, json::value_t::object))
            if (const json* lp =
                    opt(*ext, "KHR_lights_punctual", join(p, "extensions"), json::value_t::object)) {
                const std::string lpp = join(p, "extensions.KHR_lights_punctual");
                required(*lp, "light", lpp);
                check_id((*lp)["light"], join(lpp, "light"), "extensions.KHR_lights_punctual.lights",
                         light_array().size());
            }
    }

    // The document's KHR_lights_punctual.lights, for index checks (an empty array when absent).
    const json& light_array() const {
        static const json empty = json::array();
        auto e = m_doc.find("extensions");
        if (e == m_doc.end() || !e->is_object()) return empty;
        auto l = e->find("KHR_lights_punctual");
        if (l == e->end() || !l->is_object()) return empty;
        auto a = l->find("lights");
        return a != l->end() && a->is_array() ? *a : empty;
    }

    void mesh(const json& m, const std::string& p) const {
        string(m, "name", p);
        required(m, "primitives", p);
        const json& prims = m["primitives"];
        if (!prims.is_array() || prims.empty())
            fail(join(p, "primitives"), std::string("expected a non-empty array of objects, got ") +
                                            (prims.is_array() ? "an empty array" : kind(prims)));
        each(m, "primitives", p, [&](const json& prim, const std::string& pp) {
            required(prim, "attributes", pp);
            const json* attrs = opt(prim, "attributes", pp, json::value_t::object);
            for (const auto& [name, value] : attrs->items())
                check_id(value, join(pp, "attributes") + "." + name, "accessors");
            integer_id(prim, "indices", pp, "accessors");
            integer_id(prim, "material", pp, "materials");
            integer(prim, "mode", pp, 0, 6);
        });
    }

    void accessor(const json& a, const std::string& p) const {
        integer_id(a, "bufferView", p, "bufferViews");
        integer(a, "byteOffset", p, 0, 1e18);
        required(a, "componentType", p);
        const double ct = *integer(a, "componentType", p, 0, 1e9);
        if (ct != 5120 && ct != 5121 && ct != 5122 && ct != 5123 && ct != 5125 && ct != 5126)
            fail(join(p, "componentType"), number_text(ct) +
                                               " is not a glTF component type (5120, 5121, 5122, "
                                               "5123, 5125 or 5126)");
        boolean(a, "normalized", p);
        required(a, "count", p);
        integer(a, "count", p, 1, 1e18);
        required(a, "type", p);
        one_of(a, "type", p, {"SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"});
        numbers(a, "max", p, 0);
        numbers(a, "min", p, 0);
        opt(a, "sparse", p, json::value_t::object);
    }

    void buffer_view(const json& v, const std::string& p) const {
        required(v, "buffer", p);
        integer_id(v, "buffer", p, "buffers");
        integer(v, "byteOffset", p, 0, 1e18);
        required(v, "byteLength", p);
        integer(v, "byteLength", p, 1, 1e18);
        integer(v, "byteStride", p, 4, 252);
        integer(v, "target", p, 0, 1e9);
    }

    void texture_info(const json& obj, const char* key, const std::string& path) const {
        const json* t = opt(obj, key, path, json::value_t::object);
        if (!t) return;
        const std::string p = join(path, key);
        required(*t, "index", p);
        integer_id(*t, "index", p, "textures");
        integer(*t, "texCoord", p, 0, 1e9);
        number(*t, "scale", p);
        number(*t, "strength", p);
    }

    // Factors the spec bounds to [0, 1] are type-checked here and clamped (with a warning) by MaterialTable;
    // numbers whose range has no sensible nearest value (a negative strength, an ior below 1) are errors.
    void material(const json& m, const std::string& p) const {
        string(m, "name", p);
        if (const json* pbr = opt(m, "pbrMetallicRoughness", p, json::value_t::object)) {
            const std::string pp = join(p, "pbrMetallicRoughness");
            numbers(*pbr, "baseColorFactor", pp, 4);
            number(*pbr, "metallicFactor", pp);
            number(*pbr, "roughnessFactor", pp);
            texture_info(*pbr, "baseColorTexture", pp);
            texture_info(*pbr, "metallicRoughnessTexture", pp);
        }
        texture_info(m, "normalTexture", p);
        texture_info(m, "occlusionTexture", p);
        texture_info(m, "emissiveTexture", p);
        numbers(m, "emissiveFactor", p, 3);
        one_of(m, "alphaMode", p, {"OPAQUE", "MASK", "BLEND"});
        number(m, "alphaCutoff", p, k_non_negative);
        boolean(m, "doubleSided", p);
        const json* ext = opt(m, "extensions", p, json::value_t::object);
        if (!ext) return;
        const std::string ep = join(p, "extensions");
        if (const json* e = opt(*ext, "KHR_materials_emissive_strength", ep, json::value_t::object))
            number(*e, "emissiveStrength", join(ep, "KHR_materials_emissive_strength"), k_non_negative);
        if (const json* e = opt(*ext, "KHR_materials_specular", ep, json::value_t::object)) {
            const std::string sp = join(ep, "KHR_materials_specular");
            number(*e, "specularFactor", sp);
            numbers(*e, "specularColorFactor", sp, 3);
            texture_info(*e, "specularTexture", sp);
            texture_info(*e, "specularColorTexture", sp);
        }
        if (const json* e = opt(*ext, "KHR_materials_transmission", ep, json::value_t::object)) {
            const std::string tp = join(ep, "KHR_materials_transmission");
            number(*e, "transmissionFactor", tp);
            texture_info(*e, "transmissionTexture", tp);
        }
        if (const json* e = opt(*ext, "KHR_materials_ior", ep, json::value_t::object))
            number(*e, "ior", join(ep, "KHR_materials_ior"), Range{1.0, INFINITY, false, false});
    }

    void camera(const json& c, const std::string& p) const {
        string(c, "name", p);
        required(c, "type", p);
        one_of(c, "type", p, {"perspective", "orthographic"});
        if (c["type"] == "perspective") {
            required(c, "perspective", p);
            const json* per = opt(c, "perspective", p, json::value_t::object);
            const std::string pp = join(p, "perspective");
            required(*per, "yfov", pp);
            number(*per, "yfov", pp, Range{0.0, k_pi, true, true});
            number(*per, "aspectRatio", pp, k_positive);
            const auto znear = number(*per, "znear", pp, k_positive);
            if (const auto zfar = number(*per, "zfar", pp, k_positive); zfar && znear && !(*zfar > *znear))
                fail(join(pp, "zfar"),
                     number_text(*zfar) + " must exceed znear (" + number_text(*znear) + ")");
        } else if (const json* o = opt(c, "orthographic", p, json::value_t::object)) {
            const std::string op = join(p, "orthographic");
            for (const char* k : {"xmag", "ymag", "znear", "zfar"}) number(*o, k, op);
        }
    }

    void light(const json& l, const std::string& p) const {
        string(l, "name", p);
        required(l, "type", p);
        one_of(l, "type", p, {"point", "spot", "directional"});
        numbers(l, "color", p, 3);
        number(l, "intensity", p, k_non_negative);
        number(l, "range", p, k_positive);
        if (const json* s = opt(l, "spot", p, json::value_t::object)) {
            const std::string sp = join(p, "spot");
            const double inner =
                number(*s, "innerConeAngle", sp, Range{0.0, k_pi / 2, false, true}).value_or(0.0);
            const double outer =
                number(*s, "outerConeAngle", sp, Range{0.0, k_pi / 2, true, false}).value_or(k_pi / 4);
            if (!(inner < outer))
                fail(join(sp, "innerConeAngle"),
                     number_text(inner) + " must be below outerConeAngle (" + number_text(outer) + ")");
        }
    }

    const json& m_doc;
    const std::string& m_file;
};

}  // namespace

void check_schema(const json& doc, const std::string& file) { Checker(doc, file).run(); }

}  // namespace npt::scene::gltf
