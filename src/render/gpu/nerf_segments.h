// The NeRF pass of the wavefront path tracer (wavefront.h): after each OptiX launch it gathers the paths that
// go on and the NeRF segments they left queued, marches every segment through its model's occupancy grid a
// few samples per round (the rounds of `nerfpt view`'s GPU renderer), evaluates the samples with the
// hash-grid kernel and the fused tensor-core MLP (fp16) and composites them exactly as media::march_nerf does
// (the same samples, lattice offset, scales and stopping point), writing each result back into its path. A relit
// NeRF's samples are evaluated for their density only: its radiance segments are free flights (the first sample
// where the optical depth reaches the path's target, as media::march_relit finds it), its shadow segments
// transmittance. Host code; the kernels are in nerf_segment_kernels.cu.
#pragma once

#include <cuda_fp16.h>
#include <cuda_runtime.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/cuda/device_buffer.h"
#include "media/volume.h"
#include "render/gpu/path_store.h"

namespace npt::gpu {

// One NeRF of the pass as its kernels see it.
struct NerfSegmentModel {
    nerf::NerfLayout layout;
    const float* params = nullptr;     // device, fp32 (the scene's copy)
    const __half* mlp_half = nullptr;  // device, the fused MLP's weights
    nerf::MarchParams march;
    nerf::OccupancyGridView grid;  // bit fields on the device
    Vec3 box_min, box_max;         // around the occupied cells
    float density_scale = 1.0f, emission_scale = 1.0f;
    bool relit = false;  // radiance segments are free flights (FlightEvent), never emission
    int32_t volume = -1;  // its index in the scene's volumes (FlightEvent::volume)
};

// How the pass splits its rounds. The defaults were measured on the H200 (docs/benchmarks.md, issue 13);
// tests force either form.
struct NerfPassTuning {
    // A round of at most this many live segments marches and composites each with a whole warp (uniform steps
    // only): the long segments of a round's tail are then not one thread's long dependent chain. 0: never.
    // NERFPT_SEGMENT_WARP_BELOW overrides the default (a benchmark knob). Measured on the NeRF demo at 1080p
    // (docs/gpu_runs/optix9_warp_below.log): 0 49 frames/s, 2^13 56, 2^15 57, 2^17 59.5, 2^19 58.
    uint32_t warp_below = 1u << 17;
    // Samples per segment and round at most; rounds double up to it (RenderSlots::used holds 255).
    int max_round = 128;
    int max_warp_round = 255;
    static NerfPassTuning defaults();
};

class NerfSegmentPass {
  public:
    // host: the scene's volumes with host pointers (SceneData); device: the same on the device (DeviceScene).
    // Every NeRF whose network the fp16 kernels support gets a slot; `max_paths` bounds the paths of a wave.
    NerfSegmentPass(Span<const media::VolumeView> host, Span<const media::VolumeView> device,
                    size_t max_paths, cudaStream_t stream);
    ~NerfSegmentPass();
    NerfSegmentPass(const NerfSegmentPass&) = delete;
    NerfSegmentPass& operator=(const NerfSegmentPass&) = delete;

    // False when no volume of the scene is a NeRF the pass takes (nothing to gain from the wavefront form).
    bool any() const { return !m_models.empty(); }
    // Per scene volume: its slot, or k_no_query (device array, WavefrontParams::nerf_slot).
    const uint32_t* nerf_slots() const { return m_slot_of_volume.data(); }

    // The n paths of `active` (null: paths 0 .. n-1) after a launch, `queue` their queue_words: those that go
    // on are listed in `next` (returned: how many), and every queued segment is evaluated into its path.
    uint32_t run(const PathStore& paths, const uint32_t* queue, const uint32_t* active, uint32_t n,
                 uint32_t* next);

    // Since the last call: segments evaluated and rounds; then the counts restart.
    std::string stats();

    void set_tuning(const NerfPassTuning& t) { m_tuning = t; }

  private:
    struct Buffers;
    void evaluate(const PathStore& paths, size_t model, uint32_t n);
    uint32_t read(const uint32_t* device_count);

    cudaStream_t m_stream;
    std::vector<NerfSegmentModel> m_models;
    std::vector<DeviceBuffer<__half>> m_mlp_half;
    std::vector<DeviceBuffer<uint32_t>> m_bits;
    DeviceBuffer<uint32_t> m_slot_of_volume;
    std::unique_ptr<Buffers> m_buf;
    NerfPassTuning m_tuning = NerfPassTuning::defaults();
    uint64_t m_segments = 0, m_shadow_segments = 0, m_rounds = 0, m_warp_rounds = 0;
};

}  // namespace npt::gpu
