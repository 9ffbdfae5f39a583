#include "render/gpu/nerf_segments.h"

#include <algorithm>
#include <cstdlib>
#include <string>

#include "nerf/cuda/adam_kernels.h"
#include "nerf/cuda/fused_mlp.h"
#include "nerf/cuda/occupancy_bits.h"
#include "nerf/cuda/render_kernels.h"
#include "nerf/cuda/sample_slots.h"
#include "render/gpu/nerf_segment_kernels.h"

namespace npt::gpu {

namespace {
// Rounds as in the view renderer (cuda_renderer.cpp), samples per live segment doubling from round to round,
// but the first round takes about k_round_samples samples in all: a long list starts with 8 per segment (few
// evaluated past the point where a segment turns opaque), a short one (later bounces) with up to 128, so it
// ends in a round or two instead of a handful of nearly empty ones, each with a synchronisation.
constexpr int k_min_first_round = 8;
constexpr uint32_t k_round_samples = 1u << 22;
// The sample buffers: 8 per path of a wave, between 4 and 16 million (about 120 bytes each).
constexpr size_t k_min_samples = size_t(1) << 22, k_max_samples = size_t(1) << 24;
constexpr uint32_t k_shadow_count = 4;  // where Buffers::counts holds the queued shadow segments (stats)
constexpr uint32_t k_list_counts = 5;   // where the lists' lengths start in Buffers::counts

int first_round(uint32_t segments, int max_round) {
    int k = k_min_first_round;
    while (k < max_round && uint64_t(k) * segments < k_round_samples) k *= 2;
    return std::min(k, max_round);
}
}  // namespace

NerfPassTuning NerfPassTuning::defaults() {
    NerfPassTuning t;
    if (const char* e = std::getenv("NERFPT_SEGMENT_WARP_BELOW"))
        t.warp_below = uint32_t(std::strtoul(e, nullptr, 10));
    return t;
}

struct NerfSegmentPass::Buffers {
    size_t paths = 0, segments = 0, samples = 0;
    // counts: [0] next paths, [1] live a, [2] live b, [3] samples, [4] shadow segments queued (stats), [5
    // ...] each list's length.
    DeviceBuffer<uint32_t> lists, counts;
    DeviceBuffer<SegmentState> states;
    DeviceBuffer<Vec3> dirs;
    DeviceBuffer<uint32_t> live[2];
    nerf::cuda::SampleSlotBuffers slots;  // b.samples slots, b.segments rays
    std::vector<uint32_t> host_counts;
};

NerfSegmentPass::NerfSegmentPass(Span<const media::VolumeView> host, Span<const media::VolumeView> device,
                                 size_t max_paths, cudaStream_t stream)
    : m_stream(stream), m_buf(std::make_unique<Buffers>()) {
    // The device views hold the device pointers of the models' parameters (DeviceVolumes).
    std::vector<media::VolumeView> dev(device.size);
    if (device.size)
        cuda_check(cudaMemcpy(dev.data(), device.data, device.size * sizeof(media::VolumeView),
                              cudaMemcpyDeviceToHost),
                   "cudaMemcpy");
    std::vector<uint32_t> slot_of(host.size, k_no_query);
    m_bits.reserve(2 * host.size);
    m_mlp_half.reserve(host.size);
    for (size_t i = 0; i < host.size; ++i) {
        const media::VolumeView& v = host[i];
        if (v.kind != media::VolumeKind::Nerf) continue;
        if (m_models.size() + 1 >= k_max_queue_slot) continue;  // (32766 NeRFs in a scene) integrated inline
        std::string why;
        if (!nerf::cuda::mlp_shape_supported(v.nerf.field.layout, &why)) continue;  // integrated inline
        NerfSegmentModel m;
        m.layout = v.nerf.field.layout;
        m.params = dev[i].nerf.field.params;
        m_mlp_half.emplace_back(nerf::cuda::k_mlp_half_weights, "the NeRF's fp16 weights", "");
        cuda_check(cudaMemsetAsync(m_mlp_half.back().data(), 0, m_mlp_half.back().bytes(), stream),
                   "cudaMemsetAsync");
        nerf::cuda::to_half(m.params, uint32_t(nerf::cuda::k_mlp_param_count), m_mlp_half.back().data(),
                            stream);
        m.mlp_half = m_mlp_half.back().data();
        m.march = v.nerf.march;
        const nerf::cuda::OccupancyBits bits = nerf::cuda::occupancy_bits(v.nerf.occupancy);
        m_bits.emplace_back();
        m_bits.back().upload(bits.occupied, "the occupancy grid", "");
        m.grid = {nullptr, v.nerf.occupancy.cascades, v.nerf.occupancy.resolution, m_bits.back().data(),
                  nullptr};
        if (!bits.coarse.empty()) {
            m_bits.emplace_back();
            m_bits.back().upload(bits.coarse, "the occupancy grid", "");
            m.grid.coarse_bits = m_bits.back().data();
        }
        m.box_min = bits.box_min;
        m.box_max = bits.box_max;
        m.density_scale = v.density_scale;
        m.emission_scale = v.emission_scale;
        m.relit = v.nerf.relit;
        m.volume = int32_t(i);
        slot_of[i] = uint32_t(m_models.size());
        m_models.push_back(m);
    }
    m_slot_of_volume.upload(slot_of, "the volume table", "");

    Buffers& b = *m_buf;
    b.paths = std::max<size_t>(max_paths, 1);
    b.segments = 2 * b.paths;  // a volume and a shadow segment per path at most
    // At least one sample per segment, so that every live segment takes part in every round.
    b.samples =
        std::max((b.segments + 127) / 128 * 128, std::clamp(8 * b.paths, k_min_samples, k_max_samples));
    const size_t lists = m_models.size();
    const char* lower = "--res or --spp";
    b.lists.allocate(std::max<size_t>(lists, 1) * b.segments, "the NeRF segment lists", lower);
    b.counts.allocate(k_list_counts + lists);
    b.host_counts.resize(k_list_counts + lists);
    b.states.allocate(b.segments, "the NeRF segments", lower);
    b.dirs.allocate(b.segments, "the NeRF segments", lower);
    b.live[0].allocate(b.segments, "the NeRF segments", lower);
    b.live[1].allocate(b.segments, "the NeRF segments", lower);
    b.slots.allocate(b.samples, b.segments, true, "the NeRF samples", lower);
    cuda_check(cudaStreamSynchronize(stream), "preparing the NeRF pass");
}

NerfSegmentPass::~NerfSegmentPass() = default;

uint32_t NerfSegmentPass::read(const uint32_t* device_count) {
    uint32_t v = 0;
    cuda_check(cudaMemcpyAsync(&v, device_count, sizeof v, cudaMemcpyDeviceToHost, m_stream),
               "cudaMemcpyAsync");
    cuda_check(cudaStreamSynchronize(m_stream), "the NeRF pass");
    return v;
}

uint32_t NerfSegmentPass::run(const PathStore& paths, const uint32_t* queue, const uint32_t* active,
                              uint32_t n, uint32_t* next) {
    Buffers& b = *m_buf;
    const uint32_t lists = uint32_t(m_models.size());
    cuda_check(cudaMemsetAsync(b.counts.data(), 0, b.counts.bytes(), m_stream), "cudaMemsetAsync");
    SegmentLists l{b.lists.data(), b.counts.data() + k_list_counts, uint32_t(b.segments), lists,
                   b.counts.data() + k_shadow_count};
    segment_gather(queue, active, n, next, b.counts.data(), l, m_stream);
    cuda_check(cudaMemcpyAsync(b.host_counts.data(), b.counts.data(), b.counts.bytes(),
                               cudaMemcpyDeviceToHost, m_stream),
               "cudaMemcpyAsync");
    cuda_check(cudaStreamSynchronize(m_stream), "the NeRF pass");
    const std::vector<uint32_t> counts = b.host_counts;
    m_shadow_segments += counts[k_shadow_count];
    for (uint32_t i = 0; i < lists; ++i)
        if (counts[k_list_counts + i] > 0) evaluate(paths, i, counts[k_list_counts + i]);
    return counts[0];
}

std::string NerfSegmentPass::stats() {
    std::string s = std::to_string(m_segments) + " segments (" + std::to_string(m_shadow_segments) +
                    " of them shadow rays') in " + std::to_string(m_rounds) + " rounds, " +
                    std::to_string(m_warp_rounds) + " of them a warp per segment";
    m_segments = m_shadow_segments = m_rounds = m_warp_rounds = 0;
    return s;
}

void NerfSegmentPass::evaluate(const PathStore& paths, size_t model, uint32_t n) {
    Buffers& b = *m_buf;
    m_segments += n;
    const NerfSegmentModel& m = m_models[model];
    const uint32_t* list = b.lists.data() + model * b.segments;
    uint32_t* live_count = b.counts.data() + 1;
    uint32_t* sample_count = b.counts.data() + 3;
    cuda_check(cudaMemsetAsync(live_count, 0, 2 * sizeof(uint32_t), m_stream), "cudaMemsetAsync");
    segment_start(m, paths, list, n, b.states.data(), b.dirs.data(), b.live[0].data(), live_count, m_stream);
    uint32_t live = read(live_count);
    const uint32_t capacity = uint32_t(b.samples);
    const NerfPassTuning& t = m_tuning;
    const nerf::cuda::RenderSlots samples = b.slots.view(sample_count);
    // The warp form needs the global lattice of uniform steps.
    const uint32_t warp_below = m.march.cone_angle == 0.0f ? t.warp_below : 0u;
    const int max_round = std::clamp(t.max_round, 1, 255),
              max_warp_round = std::clamp(t.max_warp_round, 1, 255);
    int cur = 0;
    for (int k = first_round(live, max_round); live > 0; k *= 2) {
        ++m_rounds;
        const bool by_warp = live <= warp_below;
        m_warp_rounds += by_warp ? 1 : 0;
        k = std::min(k, by_warp ? max_warp_round : max_round);
        const int kk = int(std::max<uint32_t>(1, std::min<uint32_t>(uint32_t(k), capacity / live)));
        cuda_check(cudaMemsetAsync(sample_count, 0, sizeof(uint32_t), m_stream), "cudaMemsetAsync");
        segment_march(m, b.states.data(), b.live[cur].data(), live, kk, by_warp, samples, m_stream);
        // With colour for every sample of an emissive model: the shadow segments' colour is not needed, but
        // evaluating both kinds in the same rounds halves the rounds (and their synchronisations); packing
        // the shadow samples apart for a density-only evaluation was measured at no gain (docs/benchmarks.md,
        // issue 13). A relit model never needs the colour.
        const uint32_t rows = nerf::cuda::field_rows(uint64_t(live) * uint64_t(kk), capacity);
        if (m.relit)
            nerf::cuda::render_density_fp16(m.layout, m.params, m.mlp_half, samples, rows,
                                            b.slots.encoded.data(), b.slots.sigma.data(), m_stream);
        else
            nerf::cuda::render_field_fp16(m.layout, m.params, m.mlp_half, samples, b.dirs.data(), rows,
                                          b.slots.encoded.data(), b.slots.sigma.data(), b.slots.rgb.data(),
                                          m_stream);
        const int nxt = 1 - cur;
        uint32_t* next_count = b.counts.data() + 1 + nxt;
        cuda_check(cudaMemsetAsync(next_count, 0, sizeof(uint32_t), m_stream), "cudaMemsetAsync");
        segment_composite(m, paths, list, b.states.data(), b.live[cur].data(), live, by_warp, samples,
                          b.slots.sigma.data(), b.slots.rgb.data(), b.live[nxt].data(), next_count, m_stream);
        live = read(next_count);
        cur = nxt;
    }
}

}  // namespace npt::gpu
