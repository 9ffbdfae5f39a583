#include "render/gpu/optix_accel.h"

#include <optix.h>
#include <optix_stubs.h>

#include "render/gpu/optix_context.h"

namespace npt::gpu {

OptixAccel::OptixAccel(OptixDeviceContext ctx, const DeviceScene& scene, cudaStream_t stream) {
    const render::SceneView& view = scene.view();
    std::vector<render::MeshView> meshes(view.meshes.size);
    if (view.meshes.size)
        cuda_check(cudaMemcpy(meshes.data(), view.meshes.data, meshes.size() * sizeof(render::MeshView),
                              cudaMemcpyDeviceToHost),
                   "cudaMemcpy");
    const unsigned int flags = OPTIX_GEOMETRY_FLAG_DISABLE_ANYHIT;
    std::vector<CUdeviceptr> vertices;  // the build inputs point into these: sized once, never moved
    vertices.reserve(scene.mesh_count());
    std::vector<OptixBuildInput> inputs;
    for (size_t i = 0; i < scene.mesh_count(); ++i) {
        if (meshes[i].triangle_count == 0) continue;
        vertices.push_back(CUdeviceptr(scene.positions(i).data()));
        OptixBuildInput input{};
        input.type = OPTIX_BUILD_INPUT_TYPE_TRIANGLES;
        OptixBuildInputTriangleArray& t = input.triangleArray;
        t.vertexFormat = OPTIX_VERTEX_FORMAT_FLOAT3;
        t.vertexStrideInBytes = sizeof(Vec3);
        t.numVertices = unsigned(scene.positions(i).size());
        t.vertexBuffers = &vertices.back();
        t.indexFormat = OPTIX_INDICES_FORMAT_UNSIGNED_INT3;
        t.indexStrideInBytes = 3 * sizeof(uint32_t);
        t.numIndexTriplets = meshes[i].triangle_count;
        t.indexBuffer = CUdeviceptr(scene.indices(i).data());
        t.flags = &flags;
        t.numSbtRecords = 1;
        inputs.push_back(input);
        m_input_meshes.push_back(uint32_t(i));
    }
    if (inputs.empty()) return;  // nothing to hit: every ray misses

    OptixAccelBuildOptions options{};
    options.buildFlags = OPTIX_BUILD_FLAG_PREFER_FAST_TRACE | OPTIX_BUILD_FLAG_ALLOW_COMPACTION;
    options.operation = OPTIX_BUILD_OPERATION_BUILD;
    const unsigned n = unsigned(inputs.size());
    OptixAccelBufferSizes sizes{};
    optix_check(optixAccelComputeMemoryUsage(ctx, &options, inputs.data(), n, &sizes),
                "optixAccelComputeMemoryUsage");
    DeviceBuffer<unsigned char> temp(sizes.tempSizeInBytes, "acceleration structure scratch", "the scene's size");
    DeviceBuffer<unsigned char> full(sizes.outputSizeInBytes, "the acceleration structure", "the scene's size");
    DeviceBuffer<uint64_t> compacted_size(1);
    OptixAccelEmitDesc emit{};
    emit.type = OPTIX_PROPERTY_TYPE_COMPACTED_SIZE;
    emit.result = CUdeviceptr(compacted_size.data());
    optix_check(optixAccelBuild(ctx, stream, &options, inputs.data(), n, CUdeviceptr(temp.data()), temp.bytes(),
                                CUdeviceptr(full.data()), full.bytes(), &m_root, &emit, 1),
                "optixAccelBuild");
    cuda_check(cudaStreamSynchronize(stream), "building the acceleration structure");
    const uint64_t size = compacted_size.download()[0];
    if (size >= full.bytes()) {
        m_gas = std::move(full);
        return;
    }
    m_gas.allocate(size, "the acceleration structure", "the scene's size");
    optix_check(optixAccelCompact(ctx, stream, m_root, CUdeviceptr(m_gas.data()), size, &m_root),
                "optixAccelCompact");
    cuda_check(cudaStreamSynchronize(stream), "compacting the acceleration structure");
}

}  // namespace npt::gpu
