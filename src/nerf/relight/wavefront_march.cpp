#include "nerf/relight/wavefront_march.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "nerf/ray_march.h"

namespace npt::nerf {

namespace {

constexpr int k_round_samples = 32;  // samples a live ray takes per round

}  // namespace

void march_wavefront(const NerfModel& model, FieldQuery& query, std::vector<WaveRay>& rays, WaveMode mode) {
    if (query.march(rays, mode)) return;
    const MarchParams mp = model.march_params();
    const OccupancyGridView grid = model.occupancy.view();
    const bool color = mode == WaveMode::radiance;
    std::vector<MarchCursor> cursors(rays.size());
    std::vector<float> log_t(rays.size(), 0.0f), tau(rays.size(), 0.0f);
    std::vector<uint32_t> live;
    for (size_t i = 0; i < rays.size(); ++i) {
        WaveRay& r = rays[i];
        r.transmittance = 1.0f;
        r.radiance = Rgb(0.0f);
        r.depth = 0.0f;
        r.has_event = false;
        if (march_start(mp, grid, r.ray, r.jitter, &cursors[i])) live.push_back(uint32_t(i));
    }
    std::vector<Vec3> pos, dirs;
    std::vector<float> dt, sigma;
    std::vector<Rgb> rgb;
    std::vector<int> count;
    std::vector<size_t> first;
    while (!live.empty()) {
        const size_t n_live = std::min(live.size(), k_wavefront_round_rays);
        const size_t cap = n_live * k_round_samples;
        pos.resize(cap);
        dt.resize(cap);
        count.assign(n_live, 0);
        // 1. Each ray's next samples into its own slots.
        tbb::parallel_for(size_t(0), n_live, [&](size_t a) {
            const uint32_t i = live[a];
            int c = 0;
            march_continue(mp, grid, rays[i].ray, cursors[i], [&](const MarchSample& s) {
                pos[a * k_round_samples + c] = s.position;
                dt[a * k_round_samples + c] = s.dt;
                return ++c < k_round_samples;
            });
            count[a] = c;
        });
        // 2. Packed, evaluated as one batch.
        first.resize(n_live + 1);
        first[0] = 0;
        for (size_t a = 0; a < n_live; ++a) first[a + 1] = first[a] + size_t(count[a]);
        const size_t n = first[n_live];
        for (size_t a = 0; a < n_live; ++a)
            if (first[a] != a * k_round_samples)
                std::copy_n(pos.begin() + a * k_round_samples, count[a], pos.begin() + first[a]);
        sigma.resize(n);
        if (color) {
            dirs.resize(n);
            rgb.resize(n);
            for (size_t a = 0; a < n_live; ++a)
                std::fill_n(dirs.begin() + first[a], count[a], rays[live[a]].ray.d);
        }
        if (n > 0) query.evaluate(pos.data(), color ? dirs.data() : nullptr, n, sigma.data(), color ? rgb.data() : nullptr);
        // 3. Each ray composites its samples in order; finished rays drop out.
        std::vector<uint8_t> finished(n_live, 0);
        tbb::parallel_for(size_t(0), n_live, [&](size_t a) {
            const uint32_t i = live[a];
            WaveRay& r = rays[i];
            float lt = log_t[i], tt = tau[i];
            bool stop = false;
            for (int k = 0; k < count[a] && !stop; ++k) {
                const size_t s = first[a] + size_t(k);
                stop = wave_composite(mode, r, lt, tt, pos[s], sigma[s] * dt[a * k_round_samples + k],
                                      color ? rgb[s] : Rgb(0.0f));
            }
            log_t[i] = lt;
            tau[i] = tt;
            finished[a] = stop || cursors[i].done(mp);
        });
        std::vector<uint32_t> next;
        next.reserve(live.size());
        for (size_t a = 0; a < n_live; ++a)
            if (!finished[a]) next.push_back(live[a]);
        next.insert(next.end(), live.begin() + n_live, live.end());
        live.swap(next);
    }
    for (size_t i = 0; i < rays.size(); ++i) rays[i].transmittance = wave_transmittance(mode, log_t[i], tau[i]);
}

}  // namespace npt::nerf
