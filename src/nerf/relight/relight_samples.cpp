#include "nerf/relight/relight_samples.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/rng.h"
#include "core/srgb.h"
#include "nerf/relight/relit_spawn.h"
#include "nerf/relight/surface_normals.h"
#include "nerf/relight/wavefront_march.h"

namespace npt::nerf {

namespace {

constexpr float k_two_pi = 6.28318530717959f;
constexpr float k_golden = 0.6180339887498949f;
constexpr int k_tries_per_point = 16;  // pixels drawn for a point before giving up on it
constexpr size_t k_points_per_round = 2048;  // points whose light directions are marched together

struct Point {
    bool ok = false;
    Vec3 position, wo, normal;
    Rgb target;
    uint32_t image = 0;
    PixelRef pixel;
    Ray ray;  // model space: the camera ray the event was drawn on
};

// Draws 2..D of each found point's event: its camera ray marched again with a new lattice offset and target
// depth (a ray that finds no event this time keeps the first draw there).
void draw_more_events(const NerfModel& model, FieldQuery& query, const std::vector<Point>& points,
                      const std::vector<size_t>& found, std::vector<Pcg32>& rngs, int draws, RelightSamples& out) {
    const size_t n = found.size(), extra = size_t(draws - 1);
    out.draws = draws;
    out.draw.resize(n * size_t(draws));
    for (size_t j = 0; j < n; ++j) out.draw[j * draws] = out.position[j];
    if (extra == 0) return;
    std::vector<WaveRay> rays(n * extra);
    for (size_t j = 0; j < n; ++j)
        for (size_t m = 0; m < extra; ++m) {
            Pcg32& rng = rngs[found[j]];
            WaveRay& r = rays[j * extra + m];
            r.ray = points[found[j]].ray;
            r.jitter = rng.next_float();
            r.tau_target = -std::log1p(-std::min(rng.next_float(), 0.999999f));
        }
    march_wavefront(model, query, rays, WaveMode::event);
    for (size_t j = 0; j < n; ++j)
        for (size_t m = 0; m < extra; ++m) {
            const WaveRay& r = rays[j * extra + m];
            out.draw[j * draws + 1 + m] = r.has_event ? r.event_position : out.position[j];
        }
}

}  // namespace

RelightSamples gather_relight_samples(const NerfModel& model, const Dataset& data, FieldQuery& query,
                                      const RelightSampleSettings& settings, const RelightProgressFn& progress) {
    if (data.cameras.empty()) throw Error("the relight stage needs training images; the data set has none");
    if (settings.points < 1 || settings.directions < 1 || settings.event_draws < 1)
        throw Error("relight: points, directions and event draws must be at least 1");
    const size_t n_points = size_t(settings.points);
    const int K = settings.directions;
    const Mat4& w2m = model.world_to_model;
    const uint8_t min_alpha = uint8_t(std::lround(std::clamp(settings.min_alpha, 0.0f, 1.0f) * 255.0f));
    std::vector<Point> points(n_points);
    std::vector<Pcg32> rngs(n_points);
    for (size_t s = 0; s < n_points; ++s) rngs[s] = Pcg32(mix64(settings.seed ^ 0x72656c69676874ULL), s);

    // 1. Events: a camera ray through a random opaque pixel per point, its event drawn from the volume weights;
    // points whose ray found nothing try another pixel, up to k_tries_per_point times.
    std::vector<size_t> todo(n_points);
    for (size_t s = 0; s < n_points; ++s) todo[s] = s;
    for (int attempt = 0; attempt < k_tries_per_point && !todo.empty(); ++attempt) {
        std::vector<WaveRay> rays;
        std::vector<size_t> owner;
        std::vector<Point> pending;
        for (size_t s : todo) {
            Pcg32& rng = rngs[s];
            const uint32_t img = rng.next_u32() % uint32_t(data.cameras.size());
            const float px = rng.next_float() * float(data.width);
            const float py = rng.next_float() * float(data.height);
            const float jitter = rng.next_float(), u_event = rng.next_float();
            const int ix = std::min(int(px), data.width - 1), iy = std::min(int(py), data.height - 1);
            const uint8_t* pix = data.image(img) + (size_t(iy) * data.width + ix) * 4;
            if (pix[3] < min_alpha) continue;
            const Ray world = generate_pixel_ray(data.cameras[img], px, py);
            WaveRay r;
            r.ray = Ray{w2m.transform_point(world.o), normalize(w2m.transform_vector(world.d))};
            r.jitter = jitter;
            r.tau_target = -std::log1p(-std::min(u_event, 0.999999f));
            rays.push_back(r);
            owner.push_back(s);
            Point p;
            p.image = img;
            p.pixel = PixelRef{img, px, py, jitter};
            p.wo = -r.ray.d;
            p.ray = r.ray;
            p.target = Rgb(srgb_to_linear(pix[0] / 255.0f), srgb_to_linear(pix[1] / 255.0f),
                           srgb_to_linear(pix[2] / 255.0f));
            pending.push_back(p);
        }
        march_wavefront(model, query, rays, WaveMode::event);
        // 2. The surface normal at each event (surface_normals.h).
        std::vector<size_t> hit;
        std::vector<Vec3> at, toward;
        std::vector<PixelRef> pixels;
        for (size_t i = 0; i < rays.size(); ++i) {
            if (!rays[i].has_event) continue;
            hit.push_back(i);
            at.push_back(rays[i].event_position);
            toward.push_back(pending[i].wo);
            pixels.push_back(pending[i].pixel);
        }
        // The stencil's where it has one; the density normal for the rest (all of them under `density`).
        std::vector<Vec3> normal(hit.size(), Vec3(0.0f));
        if (settings.normals == NormalEstimator::depth_stencil)
            normal = depth_stencil_normals(model, query, data.cameras, pixels, settings.normal_pixels);
        std::vector<size_t> missing;
        std::vector<Vec3> missing_at, missing_toward;
        for (size_t h = 0; h < hit.size(); ++h)
            if (!(dot(normal[h], normal[h]) > 0.0f)) {
                missing.push_back(h);
                missing_at.push_back(at[h]);
                missing_toward.push_back(toward[h]);
            }
        const std::vector<Vec3> fallback = density_normals(query, missing_at, missing_toward, settings.normal_step);
        for (size_t m = 0; m < missing.size(); ++m) normal[missing[m]] = fallback[m];
        for (size_t h = 0; h < hit.size(); ++h) {
            if (!(dot(normal[h], normal[h]) > 0.0f)) continue;
            Point p = pending[hit[h]];
            p.normal = normal[h];
            p.position = at[h];
            p.ok = true;
            points[owner[hit[h]]] = p;
        }
        std::vector<size_t> still;
        for (size_t s : todo)
            if (!points[s].ok) still.push_back(s);
        todo.swap(still);
    }
    std::vector<size_t> found;
    for (size_t s = 0; s < n_points; ++s)
        if (points[s].ok) found.push_back(s);
    if (found.size() * 100 < n_points)
        throw Error("relight: only " + std::to_string(found.size()) + " of " + std::to_string(n_points) +
                    " training rays found the object (is the model trained, and do the images have alpha?)");

    // 3. Light directions: uniform over each normal's hemisphere (equal-area rings of a spherical Fibonacci
    // lattice, turned by a random angle per point so that points do not share directions), marched from the
    // event moved off the surface as the relit renderer moves it.
    RelightSamples out;
    out.directions = K;
    const size_t n = found.size();
    out.position.resize(n);
    out.wo.resize(n);
    out.normal.resize(n);
    out.target.resize(n);
    out.image.resize(n);
    out.dir.resize(n * K);
    out.visibility.resize(n * K);
    out.indirect.resize(n * K);
    for (size_t j = 0; j < n; ++j) {
        const Point& p = points[found[j]];
        out.position[j] = p.position;
        out.wo[j] = p.wo;
        out.normal[j] = p.normal;
        out.target[j] = p.target;
        out.image[j] = p.image;
    }
    draw_more_events(model, query, points, found, rngs, settings.event_draws, out);
    out.normal = smooth_normals(out.position, out.normal, settings.normal_smoothing);
    for (size_t j = 0; j < n; ++j)  // smoothing may turn a normal past the horizon of its own view
        if (dot(out.normal[j], out.wo[j]) < 0.0f) out.normal[j] = points[found[j]].normal;
    const float min_step = model.march_params().min_step;
    for (size_t begin = 0; begin < n; begin += k_points_per_round) {
        const size_t end = std::min(n, begin + k_points_per_round);
        std::vector<WaveRay> rays((end - begin) * K);
        tbb::parallel_for(begin, end, [&](size_t j) {
            Pcg32& rng = rngs[found[j]];
            const Frame frame = Frame::from_z(out.normal[j]);
            const float turn = rng.next_float();
            const Vec3 origin = relit_spawn_point(out.position[j], out.normal[j], min_step);
            for (int k = 0; k < K; ++k) {
                const float z = 1.0f - (float(k) + 0.5f) / float(K);
                const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
                const float phi = k_two_pi * (float(k) * k_golden + turn);
                const Vec3 d = normalize(frame.to_world(Vec3(r * std::cos(phi), r * std::sin(phi), z)));
                WaveRay& w = rays[(j - begin) * K + k];
                w.ray = Ray{origin, d};
                w.jitter = rng.next_float();
                out.dir[j * K + k] = d;
            }
        });
        march_wavefront(model, query, rays, WaveMode::radiance);
        for (size_t i = 0; i < rays.size(); ++i) {
            out.visibility[begin * K + i] = rays[i].transmittance;
            out.indirect[begin * K + i] = rays[i].radiance;
        }
        if (progress) progress(end, n);
    }
    return out;
}

}  // namespace npt::nerf
