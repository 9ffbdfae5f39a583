// What the GPU tests of the wavefront form's NeRF pass share (nerf_segments_test.cpp, nerf_flight_test.cpp): one
// run of the pass over paths and queries built on the host, as a launch would leave them (the paths as planes of
// words, PathStore, built with the same functions), and what it wrote back. Header-only, for tests.
#pragma once

#include <algorithm>
#include <vector>

#include "core/cuda/device_buffer.h"
#include "render/gpu/nerf_segments.h"

namespace npt::test {

struct NerfPassRun {
    uint32_t going_on = 0;               // the paths the pass listed to go on
    std::vector<uint32_t> listed;        // which (going_on of them, sorted)
    std::vector<gpu::WavefrontPath> paths;  // after the pass: the results written into them
    std::vector<gpu::FlightEvent> events;   // PathStore::events after the pass
};

// Runs `pass` once over `paths` (their queue words from their phases and `queries`' slots; queries[2i + kind]),
// with PathStore::events starting as `events` (one per path).
inline NerfPassRun run_nerf_pass(gpu::NerfSegmentPass& pass, const std::vector<gpu::WavefrontPath>& paths,
                                 const std::vector<gpu::NerfQuery>& queries,
                                 const std::vector<gpu::FlightEvent>& events) {
    std::vector<uint32_t> queue(paths.size());  // what a launch writes beside the paths
    for (size_t i = 0; i < paths.size(); ++i)
        queue[i] = gpu::queue_word(paths[i].phase != gpu::PathPhase::Done, queries[2 * i].slot,
                                   queries[2 * i + 1].slot);
    const uint32_t stride = uint32_t(paths.size());
    std::vector<uint4> words(size_t(gpu::k_path_words) * stride);
    for (uint32_t i = 0; i < stride; ++i) gpu::store_path({words.data(), stride, nullptr, nullptr}, i, paths[i]);
    gpu::DeviceBuffer<uint4> dev_words;
    dev_words.upload(words);
    gpu::DeviceBuffer<gpu::NerfQuery> dev_queries;
    dev_queries.upload(queries);
    gpu::DeviceBuffer<gpu::FlightEvent> dev_events;
    dev_events.upload(events);
    const gpu::PathStore dev_paths{dev_words.data(), stride, dev_queries.data(), dev_events.data()};
    gpu::DeviceBuffer<uint32_t> dev_queue;
    dev_queue.upload(queue);
    gpu::DeviceBuffer<uint32_t> next;
    next.allocate(paths.size());
    NerfPassRun r;
    r.going_on = pass.run(dev_paths, dev_queue.data(), nullptr, stride, next.data());
    r.listed = next.download();
    r.listed.resize(r.going_on);
    std::sort(r.listed.begin(), r.listed.end());
    words = dev_words.download();
    r.paths.resize(paths.size());
    for (uint32_t i = 0; i < stride; ++i) r.paths[i] = gpu::load_path({words.data(), stride, nullptr, nullptr}, i);
    r.events = dev_events.download();
    return r;
}

}  // namespace npt::test
