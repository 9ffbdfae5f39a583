#include "render/cpu/embree_scene.h"

#include <spdlog/spdlog.h>

#include <cstring>
#include <string>

#include "core/error.h"

namespace npt::render::cpu {

namespace {

void embree_error(void*, RTCError code, const char* message) {
    spdlog::error("Embree error {}: {}", int(code), message ? message : "");
}

}  // namespace

EmbreeScene::EmbreeScene(const scene::Scene& scene) {
    m_device = rtcNewDevice(nullptr);
    if (!m_device)
        throw Error("Embree: could not create a device (error " +
                    std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
    rtcSetDeviceErrorFunction(m_device, embree_error, nullptr);
    m_scene = rtcNewScene(m_device);
    rtcSetSceneBuildQuality(m_scene, RTC_BUILD_QUALITY_HIGH);
    std::vector<char> moving(scene.meshes.size(), 0);
    if (scene.animation) {
        for (const scene::MeshBinding& b : scene.animation->meshes) moving[b.mesh] = 1;
        if (!scene.animation->meshes.empty()) rtcSetSceneFlags(m_scene, RTC_SCENE_FLAG_DYNAMIC);
    }

    for (size_t i = 0; i < scene.meshes.size(); ++i) {
        const scene::Mesh& mesh = scene.meshes[i];
        RTCGeometry geom = rtcNewGeometry(m_device, RTC_GEOMETRY_TYPE_TRIANGLE);
        if (moving[i]) rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_REFIT);
        // Copied into Embree-owned buffers: Embree needs 16-byte readable padding past the last vertex.
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.positions.size()));
        auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), mesh.triangle_count()));
        if (!v || !idx) throw Error("Embree: out of memory for mesh '" + mesh.name + "'");
        std::memcpy(v, mesh.positions.data(), mesh.positions.size() * sizeof(Vec3));
        std::memcpy(idx, mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
        rtcCommitGeometry(geom);
        unsigned id = rtcAttachGeometry(m_scene, geom);
        rtcReleaseGeometry(geom);
        if (id != i) throw Error("Embree: unexpected geometry id");
    }
    rtcCommitScene(m_scene);
}

void EmbreeScene::update(const scene::Scene& scene, const scene::PoseChanges& changes) {
    if (changes.meshes.empty()) return;
    for (size_t i : changes.meshes) {
        const scene::Mesh& mesh = scene.meshes[i];
        RTCGeometry geom = rtcGetGeometry(m_scene, unsigned(i));
        // Rigid motion keeps the counts; the index buffer changes only when a mirroring scale flips the winding.
        auto* v = static_cast<float*>(rtcGetGeometryBufferData(geom, RTC_BUFFER_TYPE_VERTEX, 0));
        auto* idx = static_cast<uint32_t*>(rtcGetGeometryBufferData(geom, RTC_BUFFER_TYPE_INDEX, 0));
        if (!v || !idx) throw Error("Embree: mesh '" + mesh.name + "' has no buffers to update");
        std::memcpy(v, mesh.positions.data(), mesh.positions.size() * sizeof(Vec3));
        std::memcpy(idx, mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
        rtcUpdateGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0);
        rtcUpdateGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0);
        rtcCommitGeometry(geom);
    }
    rtcCommitScene(m_scene);
}

EmbreeScene::~EmbreeScene() {
    if (m_scene) rtcReleaseScene(m_scene);
    if (m_device) rtcReleaseDevice(m_device);
}

}  // namespace npt::render::cpu
