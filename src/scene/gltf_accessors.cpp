// Validated reads of glTF accessors. tinygltf does not check that an accessor fits its buffer view, nor the
// view its buffer, so every bound is checked here (in 64-bit arithmetic that cannot overflow) before anything
// is read or allocated: a file claiming 10^12 vertices fails with a message instead of allocating terabytes.
#include <cstring>

#include "core/error.h"
#include "scene/gltf_internal.h"

namespace npt::scene::gltf {
namespace {

struct View {
    const unsigned char* data = nullptr;  // first element
    size_t count = 0;
    size_t stride = 0;
    int component_type = 0;
    bool normalized = false;
};

size_t component_size(int type) {
    switch (type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return 1;
        case TINYGLTF_COMPONENT_TYPE_SHORT:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
            return 2;
        case TINYGLTF_COMPONENT_TYPE_INT:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        case TINYGLTF_COMPONENT_TYPE_FLOAT:
            return 4;
        case TINYGLTF_COMPONENT_TYPE_DOUBLE:
            return 8;
        default:
            return 0;
    }
}

size_t component_count(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR:
            return 1;
        case TINYGLTF_TYPE_VEC2:
            return 2;
        case TINYGLTF_TYPE_VEC3:
            return 3;
        case TINYGLTF_TYPE_VEC4:
            return 4;
        case TINYGLTF_TYPE_MAT2:
            return 4;
        case TINYGLTF_TYPE_MAT3:
            return 9;
        case TINYGLTF_TYPE_MAT4:
            return 16;
        default:
            return 0;
    }
}

View checked_view(const Context& ctx, int index, const std::string& what, int expect_type) {
    const auto& m = ctx.model;
    const std::string name = ctx.file + ": accessor " + std::to_string(index) + " (" + what + ")";
    if (index < 0 || size_t(index) >= m.accessors.size())
        throw Error(name + ": no such accessor (the file has " + std::to_string(m.accessors.size()) + ")");
    const auto& a = m.accessors[size_t(index)];
    if (a.sparse.isSparse) throw Error(name + ": sparse accessors are not supported");
    if (a.type != expect_type)
        throw Error(name + ": has type " + std::to_string(a.type) + ", expected " +
                    std::to_string(expect_type) + " (VEC2 = 2, VEC3 = 3, VEC4 = 4, SCALAR = 65)");
    const size_t elem = component_size(a.componentType) * component_count(a.type);
    if (elem == 0) throw Error(name + ": unknown componentType " + std::to_string(a.componentType));
    if (a.count == 0) return View{nullptr, 0, elem, a.componentType, a.normalized};
    if (a.bufferView < 0 || size_t(a.bufferView) >= m.bufferViews.size())
        throw Error(name + ": bufferView " + std::to_string(a.bufferView) + " does not exist");
    const auto& bv = m.bufferViews[size_t(a.bufferView)];
    const std::string view_name = "buffer view " + std::to_string(a.bufferView);
    if (bv.buffer < 0 || size_t(bv.buffer) >= m.buffers.size())
        throw Error(ctx.file + ": " + view_name + ": buffer " + std::to_string(bv.buffer) +
                    " does not exist");
    const size_t buf_len = m.buffers[size_t(bv.buffer)].data.size();
    if (bv.byteOffset > buf_len || bv.byteLength > buf_len - bv.byteOffset)
        throw Error(ctx.file + ": " + view_name + ": bytes " + std::to_string(bv.byteOffset) + ".." +
                    std::to_string(bv.byteOffset + bv.byteLength) + " lie beyond buffer " +
                    std::to_string(bv.buffer) + " of " + std::to_string(buf_len) + " bytes");
    const size_t stride = bv.byteStride ? bv.byteStride : elem;
    if (stride < elem)
        throw Error(name + ": byteStride " + std::to_string(stride) + " of " + view_name +
                    " is smaller than the element size " + std::to_string(elem));
    // 128-bit arithmetic: a count of 10^12 (or 2^64 - 1) cannot overflow, and fails here before any
    // allocation.
    using u128 = unsigned __int128;
    const u128 need = u128(a.byteOffset) + u128(stride) * u128(a.count - 1) + u128(elem);
    if (need > u128(bv.byteLength)) {
        const std::string need_text = need > u128(UINT64_MAX) ? std::string("more than 2^64")
                                                              : std::to_string((unsigned long long)need);
        throw Error(name + ": " + std::to_string(a.count) + " elements need " + need_text + " bytes but " +
                    view_name + " has " + std::to_string(bv.byteLength));
    }
    const unsigned char* base = m.buffers[size_t(bv.buffer)].data.data() + bv.byteOffset + a.byteOffset;
    return View{base, a.count, stride, a.componentType, a.normalized};
}

float read_component(const unsigned char* p, int type, bool normalized) {
    switch (type) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT: {
            float f;
            std::memcpy(&f, p, 4);
            return f;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return normalized ? float(*p) / 255.0f : float(*p);
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t v;
            std::memcpy(&v, p, 2);
            return normalized ? float(v) / 65535.0f : float(v);
        }
        default:
            return 0.0f;
    }
}

}  // namespace

std::vector<Vec3> read_vec3(const Context& ctx, int index, const std::string& what) {
    View v = checked_view(ctx, index, what, TINYGLTF_TYPE_VEC3);
    if (v.count && v.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT)
        throw Error(ctx.file + ": accessor " + std::to_string(index) + " (" + what +
                    "): componentType must be FLOAT");
    std::vector<Vec3> out(v.count);
    for (size_t i = 0; i < v.count; ++i) std::memcpy(&out[i], v.data + i * v.stride, sizeof(float) * 3);
    return out;
}

std::vector<double> read_floats(const Context& ctx, int index, int type, const std::string& what) {
    View v = checked_view(ctx, index, what, type);
    if (v.count && v.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT)
        throw Error(ctx.file + ": accessor " + std::to_string(index) + " (" + what +
                    "): componentType must be FLOAT");
    const size_t width = component_count(type);
    std::vector<double> out(v.count * width);
    for (size_t i = 0; i < v.count; ++i)
        for (size_t k = 0; k < width; ++k) {
            float f;
            std::memcpy(&f, v.data + i * v.stride + k * 4, 4);
            out[i * width + k] = f;
        }
    return out;
}

std::vector<Vec2> read_texcoords(const Context& ctx, int index, const std::string& what) {
    View v = checked_view(ctx, index, what, TINYGLTF_TYPE_VEC2);
    const bool ok = v.component_type == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                    (v.normalized && (v.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                      v.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT));
    if (v.count && !ok)
        throw Error(ctx.file + ": accessor " + std::to_string(index) + " (" + what +
                    "): componentType must be FLOAT or normalized UNSIGNED_BYTE/UNSIGNED_SHORT");
    const size_t cs = component_size(v.component_type);
    std::vector<Vec2> out(v.count);
    for (size_t i = 0; i < v.count; ++i) {
        const unsigned char* p = v.data + i * v.stride;
        out[i] = {read_component(p, v.component_type, v.normalized),
                  read_component(p + cs, v.component_type, v.normalized)};
    }
    return out;
}

std::vector<uint32_t> read_indices(const Context& ctx, int index, const std::string& what) {
    View v = checked_view(ctx, index, what, TINYGLTF_TYPE_SCALAR);
    std::vector<uint32_t> out(v.count);
    for (size_t i = 0; i < v.count; ++i) {
        const unsigned char* p = v.data + i * v.stride;
        switch (v.component_type) {
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
                out[i] = *p;
                break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                uint16_t s;
                std::memcpy(&s, p, 2);
                out[i] = s;
                break;
            }
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
                std::memcpy(&out[i], p, 4);
                break;
            default:
                throw Error(ctx.file + ": accessor " + std::to_string(index) + " (" + what +
                            "): indices must be UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT");
        }
    }
    return out;
}

}  // namespace npt::scene::gltf
