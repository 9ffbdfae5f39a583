#include "render/scene_data.h"

#include <algorithm>
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
    // No camera: look at the scene's bounding box (meshes and volume cubes) down -Z from +Z, far enough to
    // frame it with a 40 degree field of view. Bounds in double: a box of float coordinates near the float
    // limit has a diagonal no float can hold. Every scene shape must give a finite, valid view: empty, a
    // point, a line, a flat one, a huge one, one far from the origin.
    c.right = Vec3(1, 0, 0);
    c.up = Vec3(0, 1, 0);
    c.forward = Vec3(0, 0, -1);
    c.tan_half_fov_y = std::tan(0.5f * 40.0f * k_pi / 180.0f);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    const auto grow = [&](Vec3 p) {
        if (!is_finite(p)) return;
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], double(p[k]));
            hi[k] = std::max(hi[k], double(p[k]));
        }
    };
    for (const auto& m : scene.meshes)
        for (const Vec3& p : m.positions) grow(p);
    for (const auto& v : scene.volumes)
        for (int corner = 0; corner < 8; ++corner)
            grow(v.local_to_world.transform_point(Vec3(corner & 1 ? v.local_max.x : v.local_min.x,
                                                       corner & 2 ? v.local_max.y : v.local_min.y,
                                                       corner & 4 ? v.local_max.z : v.local_min.z)));
    if (!(lo[0] <= hi[0])) lo[0] = lo[1] = lo[2] = hi[0] = hi[1] = hi[2] = 0.0;
    double centre[3], diagonal2 = 0, far = 0;
    for (int k = 0; k < 3; ++k) {
        centre[k] = 0.5 * (lo[k] + hi[k]);
        diagonal2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
        far = std::max(far, std::abs(centre[k]));
    }
    // At least a millimetre, and enough float steps at the centre's magnitude that the camera does not sit
    // on it; at most what keeps the camera inside the world Embree accepts (scene::k_max_world_coordinate).
    const double radius = std::clamp(0.5 * std::sqrt(diagonal2), std::max(1e-3, 1e-5 * far),
                                     double(scene::k_max_world_coordinate));
    const double distance = radius / double(c.tan_half_fov_y) * 1.1 + radius;
    c.position = Vec3(float(centre[0]), float(centre[1]), float(centre[2] + distance));
    return c;
}

SceneData::SceneData(const scene::Scene& scene, int width, int height) : m_width(width), m_height(height) {
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

void SceneData::update(const scene::Scene& scene, const scene::PoseChanges& changes) {
    if (!changes.any()) return;
    for (size_t i : changes.meshes) {
        const scene::Mesh& m = scene.meshes[i];
        m_meshes[i].positions = m.positions.data();  // pose_scene may have reallocated the arrays
        m_meshes[i].normals = m.normals.empty() ? nullptr : m.normals.data();
        m_meshes[i].indices = m.indices.data();
    }
    if (changes.volumes)
        for (size_t i = 0; i < scene.volumes.size(); ++i) m_volumes->set_placement(i, scene.volumes[i]);
    m_view.volumes = m_volumes->views();
    // Emissive triangles, punctual lights and the scene's bounding sphere (distant lights) may all have moved:
    // the light set is rebuilt whole, as a fresh SceneData would build it.
    m_lights = std::make_unique<lights::LightSet>(scene);
    m_view.lights = m_lights->view();
    // The default view (no camera) frames the scene's bounds, which move with the meshes.
    m_view.camera = make_camera_view(scene, m_width, m_height);
}

}  // namespace npt::render
