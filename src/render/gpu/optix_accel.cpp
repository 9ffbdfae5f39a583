#include "render/gpu/optix_accel.h"

#include <optix.h>
#include <optix_stubs.h>

#include <cstring>

#include "render/gpu/optix_context.h"

namespace npt::gpu {

OptixTraversableHandle OptixAccel::build(OptixDeviceContext ctx, const OptixBuildInput& input, bool compact,
                                         DeviceBuffer<unsigned char>& out, cudaStream_t stream) {
    OptixAccelBuildOptions options{};
    options.buildFlags = OPTIX_BUILD_FLAG_PREFER_FAST_TRACE | (compact ? OPTIX_BUILD_FLAG_ALLOW_COMPACTION : 0);
    options.operation = OPTIX_BUILD_OPERATION_BUILD;
    OptixAccelBufferSizes sizes{};
    optix_check(optixAccelComputeMemoryUsage(ctx, &options, &input, 1, &sizes), "optixAccelComputeMemoryUsage");
    DeviceBuffer<unsigned char> temp(sizes.tempSizeInBytes, "acceleration structure scratch", "the scene's size");
    DeviceBuffer<unsigned char> full(sizes.outputSizeInBytes, "an acceleration structure", "the scene's size");
    DeviceBuffer<uint64_t> compacted_size(1);
    OptixAccelEmitDesc emit{};
    emit.type = OPTIX_PROPERTY_TYPE_COMPACTED_SIZE;
    emit.result = CUdeviceptr(compacted_size.data());
    OptixTraversableHandle handle = 0;
    optix_check(optixAccelBuild(ctx, stream, &options, &input, 1, CUdeviceptr(temp.data()), temp.bytes(),
                                CUdeviceptr(full.data()), full.bytes(), &handle, compact ? &emit : nullptr,
                                compact ? 1 : 0),
                "optixAccelBuild");
    cuda_check(cudaStreamSynchronize(stream), "building an acceleration structure");
    if (compact) {
        const uint64_t size = compacted_size.download()[0];
        if (size < full.bytes()) {
            out.allocate(size, "an acceleration structure", "the scene's size");
            optix_check(optixAccelCompact(ctx, stream, handle, CUdeviceptr(out.data()), size, &handle),
                        "optixAccelCompact");
            cuda_check(cudaStreamSynchronize(stream), "compacting an acceleration structure");
            return handle;
        }
    }
    out = std::move(full);
    return handle;
}

OptixAccel::OptixAccel(OptixDeviceContext ctx, const DeviceScene& scene, cudaStream_t stream) {
    const render::SceneView& view = scene.view();
    std::vector<render::MeshView> meshes(view.meshes.size);
    if (view.meshes.size)
        cuda_check(cudaMemcpy(meshes.data(), view.meshes.data, meshes.size() * sizeof(render::MeshView),
                              cudaMemcpyDeviceToHost),
                   "cudaMemcpy");
    std::vector<OptixInstance> instances;
    m_gas.resize(scene.mesh_count());
    const unsigned int flags = OPTIX_GEOMETRY_FLAG_DISABLE_ANYHIT;
    for (size_t i = 0; i < scene.mesh_count(); ++i) {
        if (meshes[i].triangle_count == 0) continue;
        CUdeviceptr vertices = CUdeviceptr(scene.positions(i).data());
        OptixBuildInput input{};
        input.type = OPTIX_BUILD_INPUT_TYPE_TRIANGLES;
        OptixBuildInputTriangleArray& t = input.triangleArray;
        t.vertexFormat = OPTIX_VERTEX_FORMAT_FLOAT3;
        t.vertexStrideInBytes = sizeof(Vec3);
        t.numVertices = unsigned(scene.positions(i).size());
        t.vertexBuffers = &vertices;
        t.indexFormat = OPTIX_INDICES_FORMAT_UNSIGNED_INT3;
        t.indexStrideInBytes = 3 * sizeof(uint32_t);
        t.numIndexTriplets = meshes[i].triangle_count;
        t.indexBuffer = CUdeviceptr(scene.indices(i).data());
        t.flags = &flags;
        t.numSbtRecords = 1;
        OptixInstance inst{};
        const float identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
        std::memcpy(inst.transform, identity, sizeof identity);
        inst.instanceId = unsigned(i);  // the mesh index, as Embree's geomID
        inst.sbtOffset = 0;
        inst.visibilityMask = 255;
        inst.flags = OPTIX_INSTANCE_FLAG_NONE;
        inst.traversableHandle = build(ctx, input, true, m_gas[i], stream);
        instances.push_back(inst);
    }
    if (instances.empty()) return;  // nothing to hit: every ray misses
    m_instances.upload(instances);
    OptixBuildInput input{};
    input.type = OPTIX_BUILD_INPUT_TYPE_INSTANCES;
    input.instanceArray.instances = CUdeviceptr(m_instances.data());
    input.instanceArray.numInstances = unsigned(instances.size());
    m_root = build(ctx, input, false, m_ias, stream);
}

size_t OptixAccel::bytes() const {
    size_t b = m_ias.bytes() + m_instances.bytes();
    for (const auto& g : m_gas) b += g.bytes();
    return b;
}

}  // namespace npt::gpu
