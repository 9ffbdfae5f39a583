#include "render/gpu/optix_pipeline.h"

#include <optix.h>
#include <optix_stack_size.h>
#include <optix_stubs.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <string>

#include "render/gpu/optix_context.h"
#include "render/gpu/optix_launch.h"

// The device programs as OptiX-IR, embedded at build time (cmake/EmbedFile.cmake): a module per file.
extern const unsigned char k_optix_programs_ir[];
extern const size_t k_optix_programs_ir_size;
extern const unsigned char k_optix_wavefront_programs_ir[];
extern const size_t k_optix_wavefront_programs_ir_size;

namespace npt::gpu {

namespace {

struct alignas(OPTIX_SBT_RECORD_ALIGNMENT) Record {
    char header[OPTIX_SBT_RECORD_HEADER_SIZE];
    HitRecordData data;  // read by hit groups only
};

// The programs, in the order of the SBT: raygen, the miss records of the ray types, their hit groups.
enum Group {
    g_raygen,
    g_miss_radiance,
    g_miss_shadow,
    g_hit_radiance,
    g_hit_shadow,
    g_raygen_wavefront,
    g_count
};

std::string log_text(const char* log, size_t size) {
    return size > 1 ? std::string(log, size - 1) : std::string();
}

// The register limit of a module: `variable` from the environment when set (for measurements; 0: OptiX's
// default, 128), otherwise `fallback`.
int max_registers(const char* variable, int fallback) {
    const char* v = std::getenv(variable);
    return v ? std::atoi(v) : fallback;
}

OptixModule create_module(OptixDeviceContext ctx, const OptixPipelineCompileOptions& pipeline_options,
                          int registers, const unsigned char* ir, size_t ir_size, const char* what) {
    OptixModuleCompileOptions module_options{};
    module_options.maxRegisterCount = registers;
    module_options.optLevel = OPTIX_COMPILE_OPTIMIZATION_DEFAULT;
    module_options.debugLevel = OPTIX_COMPILE_DEBUG_LEVEL_MINIMAL;
    char log[2048];
    size_t log_size = sizeof log;
    OptixModule module = nullptr;
    const OptixResult r =
        optixModuleCreate(ctx, &module_options, &pipeline_options, reinterpret_cast<const char*>(ir), ir_size,
                          log, &log_size, &module);
    if (r != OPTIX_SUCCESS)
        optix_check(r, (std::string("optixModuleCreate (") + what + "): " + log_text(log, log_size)).c_str());
    return module;
}

}  // namespace

OptixPrograms::OptixPrograms(OptixDeviceContext ctx, const std::vector<uint32_t>& input_meshes) {
    char log[2048];
    size_t log_size = sizeof log;

    OptixPipelineCompileOptions pipeline_options{};
    pipeline_options.usesMotionBlur = 0;
    pipeline_options.traversableGraphFlags = OPTIX_TRAVERSABLE_GRAPH_FLAG_ALLOW_SINGLE_GAS;
    pipeline_options.numPayloadValues = 6;    // t, mesh, primitive, u, v, found
    pipeline_options.numAttributeValues = 2;  // triangle barycentrics
    pipeline_options.exceptionFlags = OPTIX_EXCEPTION_FLAG_NONE;
    pipeline_options.pipelineLaunchParamsVariableName = "params";
    pipeline_options.usesPrimitiveTypeFlags = OPTIX_PRIMITIVE_TYPE_FLAGS_TRIANGLE;
    // The per-thread program at OptiX's default register limit (128): with the wavefront program in a module
    // of its own and path_scatter a call, cornell at 1080p ran 303-307 M samples/s against 296-298 at 96
    // (cornell_volume 54.0 against 53.1), six alternating runs on the H200 (docs/benchmarks.md).
    // NERFPT_OPTIX_MAX_REGISTERS overrides it for such measurements; the wavefront program measured the same
    // at 64, 80, 96 and 128.
    m_module = create_module(ctx, pipeline_options, max_registers("NERFPT_OPTIX_MAX_REGISTERS", 0),
                             k_optix_programs_ir, k_optix_programs_ir_size, "optix_programs");
    // The wavefront form's program, a module of its own: NERFPT_OPTIX_WAVEFRONT_REGISTERS.
    m_wavefront_module = create_module(
        ctx, pipeline_options, max_registers("NERFPT_OPTIX_WAVEFRONT_REGISTERS", 96),
        k_optix_wavefront_programs_ir, k_optix_wavefront_programs_ir_size, "optix_wavefront_programs");

    OptixProgramGroupDesc desc[g_count]{};
    desc[g_raygen].kind = OPTIX_PROGRAM_GROUP_KIND_RAYGEN;
    desc[g_raygen].raygen = {m_module, "__raygen__render"};
    desc[g_raygen_wavefront].kind = OPTIX_PROGRAM_GROUP_KIND_RAYGEN;
    desc[g_raygen_wavefront].raygen = {m_wavefront_module, "__raygen__wavefront"};
    desc[g_miss_radiance].kind = OPTIX_PROGRAM_GROUP_KIND_MISS;
    desc[g_miss_radiance].miss = {m_module, "__miss__radiance"};
    desc[g_miss_shadow].kind = OPTIX_PROGRAM_GROUP_KIND_MISS;
    desc[g_miss_shadow].miss = {m_module, "__miss__shadow"};
    desc[g_hit_radiance].kind = OPTIX_PROGRAM_GROUP_KIND_HITGROUP;
    desc[g_hit_radiance].hitgroup.moduleCH = m_module;
    desc[g_hit_radiance].hitgroup.entryFunctionNameCH = "__closesthit__radiance";
    desc[g_hit_shadow].kind = OPTIX_PROGRAM_GROUP_KIND_HITGROUP;  // shadow rays need no program on a hit
    OptixProgramGroupOptions group_options{};
    m_groups.resize(g_count);
    log_size = sizeof log;
    const OptixResult gr =
        optixProgramGroupCreate(ctx, desc, g_count, &group_options, log, &log_size, m_groups.data());
    if (gr != OPTIX_SUCCESS) optix_check(gr, ("optixProgramGroupCreate: " + log_text(log, log_size)).c_str());

    OptixPipelineLinkOptions link{};
    link.maxTraceDepth = 1;  // only the ray-generation program traces
    log_size = sizeof log;
    const OptixResult pr = optixPipelineCreate(ctx, &pipeline_options, &link, m_groups.data(), g_count, log,
                                               &log_size, &m_pipeline);
    if (pr != OPTIX_SUCCESS) optix_check(pr, ("optixPipelineCreate: " + log_text(log, log_size)).c_str());

    // Stack sizes from what the programs need (the integrator keeps its state on the ray-generation stack).
    OptixStackSizes sizes{};
    for (OptixProgramGroup g : m_groups)
        optix_check(optixUtilAccumulateStackSizes(g, &sizes, m_pipeline), "optixUtilAccumulateStackSizes");
    unsigned dc_traversal = 0, dc_state = 0, continuation = 0;
    optix_check(optixUtilComputeStackSizes(&sizes, 1, 0, 0, &dc_traversal, &dc_state, &continuation),
                "optixUtilComputeStackSizes");
    // Traversable graph depth 1: a single GAS (optix_accel.h).
    optix_check(optixPipelineSetStackSize(m_pipeline, dc_traversal, dc_state, continuation, 1),
                "optixPipelineSetStackSize");

    // The shader binding table: raygen, the miss records in ray-type order, then per build input one
    // hit-group record per ray type (OptiX picks input * k_ray_types + ray type: the stride and offset
    // optixTrace passes); last, the wavefront form's raygen record (wavefront.h), which its own copy of the
    // table points to.
    const size_t hit_records = k_ray_types * std::max<size_t>(input_meshes.size(), 1);
    std::vector<Record> records(3 + hit_records + 1);
    auto pack = [&](Group g, Record& r) {
        optix_check(optixSbtRecordPackHeader(m_groups[size_t(g)], &r), "optixSbtRecordPackHeader");
    };
    pack(g_raygen, records[0]);
    pack(g_miss_radiance, records[1]);
    pack(g_miss_shadow, records[2]);
    pack(g_raygen_wavefront, records.back());
    for (size_t i = 0; k_ray_types * i < hit_records; ++i) {
        Record* hit = &records[3 + k_ray_types * i];
        pack(g_hit_radiance, hit[k_ray_radiance]);
        pack(g_hit_shadow, hit[k_ray_shadow]);
        hit[k_ray_radiance].data.mesh = hit[k_ray_shadow].data.mesh =
            i < input_meshes.size() ? input_meshes[i] : 0;
    }
    m_records.upload(reinterpret_cast<const unsigned char*>(records.data()), records.size() * sizeof(Record));
    const CUdeviceptr base = CUdeviceptr(m_records.data());
    m_sbt.raygenRecord = base;
    m_sbt.missRecordBase = base + sizeof(Record);
    m_sbt.missRecordStrideInBytes = sizeof(Record);
    m_sbt.missRecordCount = k_ray_types;
    m_sbt.hitgroupRecordBase = base + 3 * sizeof(Record);
    m_sbt.hitgroupRecordStrideInBytes = sizeof(Record);
    m_sbt.hitgroupRecordCount = unsigned(hit_records);
    m_sbt_wavefront = m_sbt;
    m_sbt_wavefront.raygenRecord = base + (records.size() - 1) * sizeof(Record);
}

OptixPrograms::~OptixPrograms() {
    if (m_pipeline) optixPipelineDestroy(m_pipeline);
    for (OptixProgramGroup g : m_groups)
        if (g) optixProgramGroupDestroy(g);
    if (m_wavefront_module) optixModuleDestroy(m_wavefront_module);
    if (m_module) optixModuleDestroy(m_module);
}

}  // namespace npt::gpu
