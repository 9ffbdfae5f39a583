#include "render/scene_data.h"

#include <cmath>

#include "core/error.h"

namespace npt::render {

namespace {

MaterialView make_material_view(const scene::Material& m) {
    MaterialView v;
    v.base_color = m.base_color;
    v.base_color_texture = m.base_color_texture;
    v.metallic = m.metallic;
    v.roughness = m.roughness;
    v.metallic_roughness_texture = m.metallic_roughness_texture;
    v.normal_texture = m.normal_texture;
    v.normal_scale = m.normal_scale;
    v.emission = m.emission;
    v.emissive_texture = m.emissive_texture;
    v.specular = m.specular;
    v.specular_color = m.specular_color;
    v.transmission = m.transmission;
    v.ior = m.ior;
    v.double_sided = m.double_sided;
    return v;
}

}  // namespace

CameraView make_camera_view(const scene::Scene& scene, int width, int height) {
    CameraView c;
    c.width = width;
    c.height = height;
    c.aspect = float(width) / float(height);
    if (scene.camera >= 0 && size_t(scene.camera) < scene.cameras.size()) {
        const scene::Camera& sc = scene.cameras[size_t(scene.camera)];
        c.position = sc.position;
        c.right = sc.right;
        c.up = sc.up;
        c.forward = sc.forward;
        c.tan_half_fov_y = std::tan(0.5f * sc.yfov);
        return c;
    }
    // No camera: look at the scene's bounding box from +Z, far enough to frame it with a 40 degree field of
    // view.
    Vec3 lo(INFINITY), hi(-INFINITY);
    for (const auto& m : scene.meshes)
        for (const Vec3& p : m.positions) {
            lo = vmin(lo, p);
            hi = vmax(hi, p);
        }
    if (!(lo.x <= hi.x)) lo = hi = Vec3(0.0f);
    Vec3 centre = (lo + hi) * 0.5f;
    float radius = std::max(0.5f * length(hi - lo), 1e-3f);
    c.tan_half_fov_y = std::tan(0.5f * 40.0f * k_pi / 180.0f);
    c.position = centre + Vec3(0, 0, radius / c.tan_half_fov_y * 1.1f + radius);
    return c;
}

SceneData::SceneData(const scene::Scene& scene, int width, int height) {
    m_materials.reserve(scene.materials.size());
    for (const auto& m : scene.materials) m_materials.push_back(make_material_view(m));
    if (m_materials.empty()) m_materials.push_back(MaterialView{});

    m_textures.reserve(scene.textures.size());
    for (const auto& t : scene.textures) m_textures.push_back(TextureView{t.rgba.data(), t.width, t.height});

    m_meshes.reserve(scene.meshes.size());
    for (const auto& m : scene.meshes) {
        MeshView v;
        v.positions = m.positions.data();
        v.normals = m.normals.empty() ? nullptr : m.normals.data();
        v.uvs = m.uvs.empty() ? nullptr : m.uvs.data();
        v.indices = m.indices.data();
        v.triangle_count = uint32_t(m.triangle_count());
        v.material = m.material >= 0 && size_t(m.material) < m_materials.size() ? uint32_t(m.material) : 0u;
        m_meshes.push_back(v);
    }
    m_lights = std::make_unique<lights::LightSet>(scene);
    m_volumes = std::make_unique<media::VolumeSet>(scene);

    m_view.meshes = {m_meshes.data(), m_meshes.size()};
    m_view.materials = {m_materials.data(), m_materials.size()};
    m_view.textures = {m_textures.data(), m_textures.size()};
    m_view.lights = m_lights->view();
    m_view.volumes = m_volumes->views();
    m_view.camera = make_camera_view(scene, width, height);
}

}  // namespace npt::render
