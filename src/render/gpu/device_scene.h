// Device copies of what a SceneView points to (meshes, materials, textures, lights, volumes with their grids or
// NeRF parameters), and the SceneView over them that device code reads: the scene the CPU renders, in GPU
// memory. Host code only.
#pragma once

#include <memory>
#include <vector>

#include "core/cuda/device_buffer.h"
#include "render/scene_view.h"

namespace npt::gpu {

template <typename T>
Span<const T> span_of(const DeviceBuffer<T>& b) {
    return {b.data(), b.size()};
}

// Every array a LightSetView points to, and the view over the copies.
class DeviceLightSet {
  public:
    explicit DeviceLightSet(const lights::LightSetView& host);
    const lights::LightSetView& view() const { return m_view; }

  private:
    TextureView upload_texture(const TextureView& t);

    lights::LightSetView m_view;
    DeviceBuffer<lights::Light> m_lights;
    DeviceBuffer<AliasBin> m_bins;
    DeviceBuffer<int32_t> m_offsets;
    DeviceBuffer<TextureView> m_textures;
    std::vector<DeviceBuffer<float>> m_texels;
    DeviceBuffer<float> m_func, m_conditional, m_marginal;
};

// A 3D texture of float4 (density, colour) with trilinear filtering and a zero border (media/grid.h).
class GridTexture {
  public:
    explicit GridTexture(const media::GridView& host);
    ~GridTexture();
    GridTexture(const GridTexture&) = delete;
    GridTexture& operator=(const GridTexture&) = delete;
    unsigned long long object() const { return m_texture; }

  private:
    cudaArray_t m_array = nullptr;
    unsigned long long m_texture = 0;
};

// The volumes: grids (density, colour, majorant; with `grid_textures` also a filtering texture each) or NeRF
// models (parameters, occupancy bytes).
class DeviceVolumes {
  public:
    explicit DeviceVolumes(Span<const media::VolumeView> host, bool grid_textures = false);
    Span<const media::VolumeView> view() const { return span_of(m_views); }
    // An animation frame: each volume's placement (world_to_local, density_scale) from `host`, the rest kept.
    void set_placements(Span<const media::VolumeView> host);

  private:
    std::vector<std::unique_ptr<GridTexture>> m_textures;
    std::vector<DeviceBuffer<float>> m_floats;
    std::vector<DeviceBuffer<Vec3>> m_colors;
    std::vector<DeviceBuffer<uint8_t>> m_bytes;
    DeviceBuffer<media::VolumeView> m_views;
};

// The whole scene.
class DeviceScene {
  public:
    // grid_textures: grids are sampled through hardware-filtered textures (the renderer's choice; the exact
    // eight-voxel lookup otherwise).
    explicit DeviceScene(const render::SceneView& host, bool grid_textures = false);
    const render::SceneView& view() const { return m_view; }
    // Per mesh, for building acceleration structures: device positions and indices.
    const DeviceBuffer<Vec3>& positions(size_t mesh) const { return m_positions[mesh]; }
    const DeviceBuffer<uint32_t>& indices(size_t mesh) const { return m_indices[mesh]; }
    size_t mesh_count() const { return m_positions.size(); }
    // An animation frame (`host` is SceneData's view after its update): the moved meshes' vertices, normals and
    // indices uploaded into their buffers (same sizes: rigid motion), the light set rebuilt, the volumes'
    // placements and the camera. The acceleration structure over the meshes is the caller's to rebuild.
    void update(const render::SceneView& host, const std::vector<size_t>& moved_meshes, bool volumes_moved);

  private:
    std::vector<DeviceBuffer<Vec3>> m_positions, m_normals;
    std::vector<DeviceBuffer<Vec2>> m_uvs;
    std::vector<DeviceBuffer<uint32_t>> m_indices;
    DeviceBuffer<render::MeshView> m_meshes;
    DeviceBuffer<render::MaterialView> m_materials;
    std::vector<DeviceBuffer<float>> m_texels;
    DeviceBuffer<TextureView> m_textures;
    DeviceLightSet m_lights;
    DeviceVolumes m_volumes;
    render::SceneView m_view;
};

}  // namespace npt::gpu
