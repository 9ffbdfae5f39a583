#include "nerf/render_view.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>

#include "core/error.h"
#include "nerf/field_batch.h"
#include "nerf/object_frame.h"

namespace npt::nerf {

namespace {

constexpr size_t k_rows_per_task = 4;
constexpr int k_first_window = 8;   // samples per ray in the first round; doubles every round
constexpr int k_max_window = 128;

struct RayState {
    size_t pixel = 0;
    uint32_t first = 0, count = 0, next = 0;  // samples [first, first + count); next = first not yet used
    float tau = 0;                            // optical depth so far (log-space transmittance)
    Rgb color{0.0f, 0.0f, 0.0f};
    Vec3 dir;
    bool done = false;
};

}  // namespace

ObjectCut view_object_cut(const NerfModel& model, const ViewOptions& options) {
    if (model.object && model.object->object_only) return object_cut(*model.object, model.world_to_model);
    if (!options.object_only) return ObjectCut{};
    if (!model.object)
        throw Error("render_view: only the object was asked for, and the model has no object frame (made by "
                    "`nerfpt capture`)");
    return object_cut(*model.object, model.world_to_model);
}

Image render_view(const NerfModel& model, const Camera& camera, const ViewOptions& options,
                  const std::function<bool(size_t, size_t)>& progress) {
    const int w = camera.width, h = camera.height;
    if (w <= 0 || h <= 0) throw Error("render_view: the camera has no pixels");
    Image img(w, h, 4);
    const NerfLayout layout = model.layout();
    const MarchParams mp = model.march_params();
    const OccupancyGridView grid = model.occupancy.view();
    const float min_t = model.config.march.min_transmittance;
    const float* params = model.params.data();
    const size_t n_tasks = (size_t(h) + k_rows_per_task - 1) / k_rows_per_task;
    const ObjectCut cut = view_object_cut(model, options);
    std::mutex progress_mutex;
    std::atomic<bool> stop{false};
    size_t rows_done = 0;

    tbb::parallel_for(size_t(0), n_tasks, [&](size_t task) {
        if (stop) return;
        const int y0 = int(task * k_rows_per_task), y1 = std::min(h, y0 + int(k_rows_per_task));
        std::vector<RayState> rays;
        std::vector<MarchSample> samples, buf(size_t(mp.max_samples));
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < w; ++x) {
                const Ray world = generate_pixel_ray(camera, float(x) + 0.5f, float(y) + 0.5f);
                const Ray ray{model.world_to_model.transform_point(world.o),
                              normalize(model.world_to_model.transform_vector(world.d))};
                RayState rs;
                rs.pixel = size_t(y) * w + x;
                rs.dir = ray.d;
                rs.first = rs.next = uint32_t(samples.size());
                // A fixed mid-step offset: an image must not change from one render to the next.
                const size_t n = march_ray(mp, grid, ray, 0.5f, buf.data());
                for (size_t s = 0; s < n; ++s)
                    if (!cut.outside(buf[s].position)) samples.push_back(buf[s]);
                rs.count = uint32_t(samples.size() - rs.first);
                rays.push_back(rs);
            }
        FieldBatch batch;
        std::vector<Vec3> pos, dirs;
        std::vector<uint32_t> owner;
        for (int window = k_first_window;; window = std::min(2 * window, k_max_window)) {
            pos.clear();
            dirs.clear();
            owner.clear();
            for (uint32_t r = 0; r < rays.size(); ++r) {
                RayState& rs = rays[r];
                if (rs.done) continue;
                const uint32_t end = std::min(rs.first + rs.count, rs.next + uint32_t(window));
                for (uint32_t s = rs.next; s < end; ++s) {
                    pos.push_back(samples[s].position);
                    dirs.push_back(rs.dir);
                    owner.push_back(r);
                }
            }
            if (pos.empty()) break;
            field_forward(layout, params, pos.data(), dirs.data(), pos.size(), true, batch);
            // Samples of a ray are consecutive and in order, so compositing runs front to back.
            for (size_t i = 0; i < pos.size(); ++i) {
                RayState& rs = rays[owner[i]];
                if (rs.done) continue;
                const MarchSample& ms = samples[rs.next++];
                const float t_before = std::exp(-rs.tau);
                const float od = batch.sigma[i] * ms.dt;
                rs.color += batch.rgb[i] * (t_before * -std::expm1(-od));
                rs.tau += od;
                if (std::exp(-rs.tau) < min_t || rs.next == rs.first + rs.count) rs.done = true;
            }
            for (RayState& rs : rays)
                if (rs.next == rs.first + rs.count) rs.done = true;
        }
        for (const RayState& rs : rays) {
            const float t = std::exp(-rs.tau);
            float* p = &img.pixels[rs.pixel * 4];
            const Rgb c = rs.color + options.background * t;
            p[0] = c.x;
            p[1] = c.y;
            p[2] = c.z;
            p[3] = 1.0f - t;
        }
        if (progress) {
            std::lock_guard lock(progress_mutex);
            rows_done += size_t(y1 - y0);
            if (!progress(rows_done, size_t(h))) stop = true;
        }
    });
    if (stop) throw Error("interrupted");
    return img;
}

}  // namespace npt::nerf
