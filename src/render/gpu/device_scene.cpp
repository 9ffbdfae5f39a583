#include "render/gpu/device_scene.h"

#include <algorithm>
#include <string>

#include "core/error.h"

namespace npt::gpu {

DeviceLightSet::DeviceLightSet(const lights::LightSetView& host) : m_view(host) {
    m_lights.upload(host.lights.data, host.lights.size);
    m_bins.upload(host.selector.bins.data, host.selector.bins.size);
    m_offsets.upload(host.mesh_light_offset.data, host.mesh_light_offset.size);
    std::vector<TextureView> textures;
    for (size_t t = 0; t < host.textures.size; ++t) textures.push_back(upload_texture(host.textures[t]));
    m_textures.upload(textures.data(), textures.size());
    m_view.lights = span_of(m_lights);
    m_view.selector.bins = span_of(m_bins);
    m_view.mesh_light_offset = span_of(m_offsets);
    m_view.textures = span_of(m_textures);

    const Distribution2DView& d = host.environment.distribution;
    m_view.environment.texture = upload_texture(host.environment.texture);
    m_func.upload(d.func.data, d.func.size);
    m_conditional.upload(d.conditional.data, d.conditional.size);
    m_marginal.upload(d.marginal_cdf.data, d.marginal_cdf.size);
    m_view.environment.distribution.func = span_of(m_func);
    m_view.environment.distribution.conditional = span_of(m_conditional);
    m_view.environment.distribution.marginal_cdf = span_of(m_marginal);
}

TextureView DeviceLightSet::upload_texture(const TextureView& t) {
    if (!t.valid()) return TextureView{};
    m_texels.emplace_back(t.rgba, size_t(t.width) * size_t(t.height) * 4);
    return TextureView{m_texels.back().data(), t.width, t.height};
}

GridTexture::GridTexture(const media::GridView& g) {
    const size_t n = size_t(g.nx) * size_t(g.ny) * size_t(g.nz);
    std::vector<float4> texels(n);
    for (size_t i = 0; i < n; ++i) texels[i] = make_float4(g.density[i], g.color[i].x, g.color[i].y, g.color[i].z);
    const cudaChannelFormatDesc format = cudaCreateChannelDesc<float4>();
    const cudaExtent extent = make_cudaExtent(size_t(g.nx), size_t(g.ny), size_t(g.nz));
    const cudaError_t e = cudaMalloc3DArray(&m_array, &format, extent);
    if (e == cudaErrorMemoryAllocation)
        throw Error("GPU out of memory: a volume's texture needs " + std::to_string(n * sizeof(float4) >> 20) +
                    " MiB (" + std::to_string(g.nx) + "x" + std::to_string(g.ny) + "x" + std::to_string(g.nz) +
                    " voxels): bake the volume at a lower resolution");
    cuda_check(e, "cudaMalloc3DArray");
    cudaMemcpy3DParms copy{};
    copy.srcPtr = make_cudaPitchedPtr(texels.data(), size_t(g.nx) * sizeof(float4), size_t(g.nx), size_t(g.ny));
    copy.dstArray = m_array;
    copy.extent = extent;
    copy.kind = cudaMemcpyHostToDevice;
    cuda_check(cudaMemcpy3D(&copy), "cudaMemcpy3D");
    cudaResourceDesc resource{};
    resource.resType = cudaResourceTypeArray;
    resource.res.array.array = m_array;
    cudaTextureDesc desc{};  // border colour zero: voxels outside the grid count as 0, as on the CPU
    for (int a = 0; a < 3; ++a) desc.addressMode[a] = cudaAddressModeBorder;
    desc.filterMode = cudaFilterModeLinear;
    desc.readMode = cudaReadModeElementType;
    desc.normalizedCoords = 0;
    cudaTextureObject_t object = 0;
    cuda_check(cudaCreateTextureObject(&object, &resource, &desc, nullptr), "cudaCreateTextureObject");
    m_texture = object;
}

GridTexture::~GridTexture() {
    if (m_texture) cudaDestroyTextureObject(cudaTextureObject_t(m_texture));
    if (m_array) cudaFreeArray(m_array);
}

DeviceVolumes::DeviceVolumes(Span<const media::VolumeView> host, bool grid_textures) {
    std::vector<media::VolumeView> views(host.data, host.data + host.size);
    // Reserve first: views keep pointers into these buffers, which must not move.
    m_floats.reserve(3 * views.size());
    m_colors.reserve(views.size());
    m_bytes.reserve(views.size());
    for (media::VolumeView& v : views) {
        if (v.kind == media::VolumeKind::Nerf) {
            // The network's parameters and the occupancy bytes; everything else in the view is plain values.
            m_floats.emplace_back(v.nerf.field.params, v.nerf.field.layout.total);
            v.nerf.field.params = m_floats.back().data();
            const size_t r = size_t(v.nerf.occupancy.resolution);
            m_bytes.emplace_back(v.nerf.occupancy.occupied, size_t(v.nerf.occupancy.cascades) * r * r * r);
            v.nerf.occupancy.occupied = m_bytes.back().data();
            v.nerf.occupancy.occupied_bits = nullptr;
            v.nerf.occupancy.coarse_bits = nullptr;
            if (v.nerf.relit) {  // the intrinsic fields' parameters (a relit model's)
                m_floats.emplace_back(v.nerf.intrinsic.params, v.nerf.intrinsic.layout.total);
                v.nerf.intrinsic.params = m_floats.back().data();
            }
            continue;
        }
        const size_t n = size_t(v.grid.nx) * size_t(v.grid.ny) * size_t(v.grid.nz);
        if (grid_textures) {
            m_textures.push_back(std::make_unique<GridTexture>(v.grid));
            v.grid.texture = m_textures.back()->object();
        }
        m_floats.emplace_back(v.grid.density, n);
        v.grid.density = m_floats.back().data();
        m_colors.emplace_back(v.grid.color, n);
        v.grid.color = m_colors.back().data();
        if (v.majorant.max_density) {
            const size_t m = size_t(v.majorant.nx) * size_t(v.majorant.ny) * size_t(v.majorant.nz);
            m_floats.emplace_back(v.majorant.max_density, m);
            v.majorant.max_density = m_floats.back().data();
        }
    }
    m_views.upload(views);
}

void DeviceVolumes::set_placements(Span<const media::VolumeView> host) {
    std::vector<media::VolumeView> views = m_views.download();
    for (size_t i = 0; i < views.size() && i < host.size; ++i) {
        views[i].world_to_local = host[i].world_to_local;
        views[i].density_scale = host[i].density_scale;
    }
    m_views.upload(views);  // the same size: the device pointers the scene view holds stay valid
}

void DeviceScene::update(const render::SceneView& host, const std::vector<size_t>& moved_meshes, bool volumes_moved) {
    for (size_t i : moved_meshes) {
        const render::MeshView& m = host.meshes[i];
        m_positions[i].upload(m.positions, m_positions[i].size());
        m_indices[i].upload(m.indices, m_indices[i].size());
        if (m.normals) m_normals[i].upload(m.normals, m_normals[i].size());
    }
    if (volumes_moved) m_volumes.set_placements(host.volumes);
    m_lights = DeviceLightSet(host.lights);
    m_view.lights = m_lights.view();
    m_view.camera = host.camera;
}

DeviceScene::DeviceScene(const render::SceneView& host, bool grid_textures)
    : m_lights(host.lights), m_volumes(host.volumes, grid_textures), m_view(host) {
    std::vector<render::MeshView> meshes(host.meshes.data, host.meshes.data + host.meshes.size);
    m_positions.reserve(meshes.size());
    m_normals.reserve(meshes.size());
    m_uvs.reserve(meshes.size());
    m_indices.reserve(meshes.size());
    for (render::MeshView& m : meshes) {
        // Vertex counts: one past the largest index.
        uint32_t vertices = 0;
        for (uint32_t i = 0; i < 3 * m.triangle_count; ++i) vertices = std::max(vertices, m.indices[i] + 1);
        m_positions.emplace_back(m.positions, vertices);
        m_indices.emplace_back(m.indices, size_t(3) * m.triangle_count);
        m.positions = m_positions.back().data();
        m.indices = m_indices.back().data();
        m_normals.emplace_back(m.normals ? DeviceBuffer<Vec3>(m.normals, vertices) : DeviceBuffer<Vec3>());
        m.normals = m.normals ? m_normals.back().data() : nullptr;
        m_uvs.emplace_back(m.uvs ? DeviceBuffer<Vec2>(m.uvs, vertices) : DeviceBuffer<Vec2>());
        m.uvs = m.uvs ? m_uvs.back().data() : nullptr;
    }
    m_meshes.upload(meshes);
    m_materials.upload(host.materials.data, host.materials.size);
    std::vector<TextureView> textures;
    m_texels.reserve(host.textures.size);
    for (size_t t = 0; t < host.textures.size; ++t) {
        const TextureView& tv = host.textures[t];
        if (!tv.valid()) {
            textures.push_back(TextureView{});
            continue;
        }
        m_texels.emplace_back(tv.rgba, size_t(tv.width) * size_t(tv.height) * 4);
        textures.push_back(TextureView{m_texels.back().data(), tv.width, tv.height});
    }
    m_textures.upload(textures);
    m_view.meshes = span_of(m_meshes);
    m_view.materials = span_of(m_materials);
    m_view.textures = span_of(m_textures);
    m_view.lights = m_lights.view();
    m_view.volumes = m_volumes.view();
}

}  // namespace npt::gpu
