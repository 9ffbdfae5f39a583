#include "nerf/relight/relight_samples.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include "core/error.h"
#include "core/rng.h"
#include "core/srgb.h"
#include "nerf/relight/relit_spawn.h"
#include "nerf/relight/surface_normals.h"
#include "nerf/relight/wavefront_march.h"

namespace npt::nerf {

namespace {

constexpr float k_golden = 0.6180339887498949f;
constexpr int k_tries_per_point = 16;        // pixels drawn for a point before giving up on it

struct Point {
    bool ok = false;
    Vec3 position, wo, normal;
    Rgb target;
    uint32_t image = 0;
    PixelRef pixel;
    Ray ray;  // model space: the camera ray the event was drawn on
};

// The optical depth at which a scattering event is drawn, from a uniform number (exponential).
float event_optical_depth(float u) { return -std::log1p(-std::min(u, 0.999999f)); }

// Another event on `ray`: a new lattice offset and target depth.
WaveRay event_redraw(const Ray& ray, Pcg32& rng) {
    WaveRay r;
    r.ray = ray;
    r.jitter = rng.next_float();
    r.tau_target = event_optical_depth(rng.next_float());
    return r;
}

// A random training pixel and its camera ray (model space) with a lattice offset and an event's optical
// depth; nullopt where the pixel is more transparent than min_alpha (its random numbers are used all the
// same).
struct PixelDraw {
    uint32_t image = 0;
    float px = 0.0f, py = 0.0f;
    WaveRay ray;
    Rgb target;  // the pixel's colour, linear
};
std::optional<PixelDraw> draw_opaque_pixel(Pcg32& rng, const Dataset& data, const Mat4& w2m,
                                           uint8_t min_alpha) {
    PixelDraw d;
    d.image = rng.next_u32() % uint32_t(data.cameras.size());
    d.px = rng.next_float() * float(data.width);
    d.py = rng.next_float() * float(data.height);
    d.ray.jitter = rng.next_float();
    d.ray.tau_target = event_optical_depth(rng.next_float());
    const int ix = std::min(int(d.px), data.width - 1), iy = std::min(int(d.py), data.height - 1);
    const uint8_t* pix = data.image(d.image) + (size_t(iy) * data.width + ix) * 4;
    if (pix[3] < min_alpha) return std::nullopt;
    const Ray world = generate_pixel_ray(data.cameras[d.image], d.px, d.py);
    d.ray.ray = Ray{w2m.transform_point(world.o), normalize(w2m.transform_vector(world.d))};
    d.target = Rgb(srgb_to_linear(pix[0] / 255.0f), srgb_to_linear(pix[1] / 255.0f),
                   srgb_to_linear(pix[2] / 255.0f));
    return d;
}

// Draws 2..D of each found point's event: its camera ray marched again with a new lattice offset and target
// depth (a ray that finds no event this time keeps the first draw there).
void draw_more_events(const NerfModel& model, FieldQuery& query, const std::vector<Point>& points,
                      const std::vector<size_t>& found, std::vector<Pcg32>& rngs, int draws,
                      RelightSamples& out) {
    const size_t n = found.size(), extra = size_t(draws - 1);
    out.draws = draws;
    out.draw.resize(n * size_t(draws));
    for (size_t j = 0; j < n; ++j) out.draw[j * draws] = out.position[j];
    if (extra == 0) return;
    std::vector<WaveRay> rays(n * extra);
    for (size_t j = 0; j < n; ++j)
        for (size_t m = 0; m < extra; ++m)
            rays[j * extra + m] = event_redraw(points[found[j]].ray, rngs[found[j]]);
    march_wavefront(model, query, rays, WaveMode::event);
    for (size_t j = 0; j < n; ++j)
        for (size_t m = 0; m < extra; ++m) {
            const WaveRay& r = rays[j * extra + m];
            out.draw[j * draws + 1 + m] = r.has_event ? r.event_position : out.position[j];
        }
}

// The lit points in a uniform grid of cell `radius`, for the nearest one to a position (27 cells a query).
class PointGrid {
  public:
    // Copies the points: the samples they come from grow while the grid is in use.
    PointGrid(const std::vector<Vec3>& points, const std::vector<Vec3>& normals, float radius)
        : m_points(points),
          m_normals(normals),
          m_radius(radius),
          m_inv(1.0f / radius),
          m_keyed(points.size()) {
        tbb::parallel_for(size_t(0), points.size(), [&](size_t i) {
            m_keyed[i] = {key_of(cell_of(points[i])), uint32_t(i)};
        });
        std::sort(m_keyed.begin(), m_keyed.end());
    }

    // The nearest point within the radius whose normal faces wo (normal . wo > 0.1); -1 where there is none.
    int64_t nearest_facing(Vec3 p, Vec3 wo) const {
        float best = m_radius * m_radius;
        int64_t found = -1;
        for_each_within(p, [&](uint32_t q, float d2) {
            if (d2 < best && dot(m_normals[q], wo) > 0.1f) {
                best = d2;
                found = q;
            }
        });
        return found;
    }

    // Up to `count` points nearest to point `self` within the radius whose normals agree with its own
    // (cosine > min_cos), nearest first, into out (cleared).
    void nearest_agreeing(uint32_t self, int count, float min_cos, std::vector<uint32_t>& out) const {
        out.clear();
        const Vec3 n = m_normals[self];
        std::vector<std::pair<float, uint32_t>> near;
        for_each_within(m_points[self], [&](uint32_t q, float d2) {
            if (q != self && dot(m_normals[q], n) > min_cos) near.push_back({d2, q});
        });
        const size_t keep = std::min(near.size(), size_t(count));
        std::partial_sort(near.begin(), near.begin() + keep, near.end());
        for (size_t i = 0; i < keep; ++i) out.push_back(near[i].second);
    }

  private:
    std::array<int64_t, 3> cell_of(Vec3 p) const {
        return {int64_t(std::floor(p.x * m_inv)), int64_t(std::floor(p.y * m_inv)),
                int64_t(std::floor(p.z * m_inv))};
    }
    // f(point, squared distance) for every point closer to p than the radius (the 27 cells around p's).
    template <class F>
    void for_each_within(Vec3 p, F&& f) const {
        const std::array<int64_t, 3> c = cell_of(p);
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const uint64_t key = key_of({c[0] + dx, c[1] + dy, c[2] + dz});
                    auto it = std::lower_bound(m_keyed.begin(), m_keyed.end(), std::make_pair(key, uint32_t(0)));
                    for (; it != m_keyed.end() && it->first == key; ++it) {
                        const Vec3 d = m_points[it->second] - p;
                        const float d2 = dot(d, d);
                        if (d2 < m_radius * m_radius) f(it->second, d2);
                    }
                }
    }
    static uint64_t key_of(const std::array<int64_t, 3>& c) {
        return (uint64_t(c[0] & 0x1fffff) << 42) | (uint64_t(c[1] & 0x1fffff) << 21) |
               uint64_t(c[2] & 0x1fffff);
    }

    std::vector<Vec3> m_points, m_normals;
    float m_radius, m_inv;
    std::vector<std::pair<uint64_t, uint32_t>> m_keyed;
};

// A search radius matched to the lit points' spacing (millions of points on a GPU lie ~30x closer than the
// CPU's thousands): 2.5x the median distance to the count-th neighbour (normals agreeing: cosine > min_cos) of
// 256 probe points, at most coarse's radius, so that a search scans about a hundred points instead of
// thousands. Coarse's radius where most probes have fewer neighbours than that within it.
float spacing_radius(const RelightSamples& out, const PointGrid& coarse, int count, float min_cos, float max_radius) {
    std::vector<float> reach;
    std::vector<uint32_t> near;
    const size_t probes = std::min<size_t>(out.lit, 256);
    for (size_t i = 0; i < probes; ++i) {
        const uint32_t j = uint32_t(i * out.lit / probes);
        coarse.nearest_agreeing(j, count, min_cos, near);
        if (near.size() == size_t(count)) reach.push_back(length(out.position[near.back()] - out.position[j]));
    }
    if (reach.size() * 2 <= probes) return max_radius;
    std::nth_element(reach.begin(), reach.begin() + std::ptrdiff_t(reach.size() / 2), reach.end());
    return std::min(max_radius, std::max(2.5f * reach[reach.size() / 2], 1e-6f));
}

// The pooled neighbours of every lit point (settings.pooled_neighbours; RelightSamples::neighbour): the nearest
// within borrow_radius whose normals agree, searched within spacing_radius.
void pool_neighbours(const RelightSampleSettings& settings, RelightSamples& out) {
    constexpr float k_min_cos = 0.9f;  // normals within ~25 degrees see about the same hemisphere
    const int M = settings.pooled_neighbours;
    const float radius = spacing_radius(out, PointGrid(out.position, out.normal, settings.borrow_radius), M,
                                        k_min_cos, settings.borrow_radius);
    const PointGrid lit_points(out.position, out.normal, radius);
    out.neighbours = M;
    out.neighbour.assign(out.lit * size_t(M), RelightSamples::k_no_neighbour);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, out.lit), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<uint32_t> near;
        for (size_t j = r.begin(); j != r.end(); ++j) {
            lit_points.nearest_agreeing(uint32_t(j), M, k_min_cos, near);
            std::copy(near.begin(), near.end(), out.neighbour.begin() + std::ptrdiff_t(j * size_t(M)));
        }
    });
}

// Appends settings.borrowing_pixels samples to `out` (whose lit points are complete): a camera ray through a
// random opaque training pixel, its event and event draws as for the points, the light of the nearest lit
// point.
void add_borrowing_pixels(const NerfModel& model, const Dataset& data, FieldQuery& query,
                          const RelightSampleSettings& settings, uint8_t min_alpha, RelightSamples& out) {
    const size_t wanted = size_t(settings.borrowing_pixels), draws = size_t(out.draws);
    const Mat4& w2m = model.world_to_model;
    out.lit = out.size();
    const PointGrid lit_points(out.position, out.normal, settings.borrow_radius);
    // The nearest facing point is looked for within the points' spacing first (exact: any nearer point lies
    // inside that radius too), within borrow_radius only where that finds none.
    const float near_radius = spacing_radius(out, lit_points, 4, -1.0f, settings.borrow_radius);
    std::optional<PointGrid> near_points;
    if (near_radius < settings.borrow_radius) near_points.emplace(out.position, out.normal, near_radius);
    constexpr size_t k_round = size_t(1) << 18;
    Pcg32 rng(mix64(settings.seed ^ 0x626f72726f77ULL), 0);
    size_t added = 0;
    // Rounds until enough pixels found a donor; pixels are drawn with replacement, so any count can be met
    // unless rounds stop finding any (no opaque pixel hits the model near a lit point).
    for (int barren = 0; barren < k_tries_per_point && added < wanted;) {
        const size_t n = std::min(k_round, wanted - added);
        std::vector<WaveRay> rays;
        std::vector<Rgb> target;
        std::vector<uint32_t> image;
        std::vector<std::array<float, 2>> pixel;
        for (size_t i = 0; i < n * 2 && rays.size() < n; ++i) {  // about half the pixels are transparent
            const std::optional<PixelDraw> d = draw_opaque_pixel(rng, data, w2m, min_alpha);
            if (!d) continue;
            rays.push_back(d->ray);
            target.push_back(d->target);
            image.push_back(d->image);
            pixel.push_back({d->px, d->py});
        }
        march_wavefront(model, query, rays, WaveMode::event);
        std::vector<size_t> hit;
        std::vector<Vec3> at, wo;
        for (size_t i = 0; i < rays.size(); ++i)
            if (rays[i].has_event) {
                hit.push_back(i);
                at.push_back(rays[i].event_position);
                wo.push_back(-rays[i].ray.d);
            }
        std::vector<int64_t> donor(hit.size());
        tbb::parallel_for(size_t(0), hit.size(),
                          [&](size_t h) {
                              donor[h] = near_points ? near_points->nearest_facing(at[h], wo[h]) : -1;
                              if (donor[h] < 0) donor[h] = lit_points.nearest_facing(at[h], wo[h]);
                          });
        // The further event draws of the pixels that found a donor, on their own camera rays.
        std::vector<size_t> kept;
        for (size_t h = 0; h < hit.size() && added + kept.size() < wanted; ++h)
            if (donor[h] >= 0) kept.push_back(h);
        std::vector<WaveRay> more(kept.size() * (draws - 1));
        for (size_t j = 0; j < kept.size(); ++j)
            for (size_t m = 0; m + 1 < draws; ++m)
                more[j * (draws - 1) + m] = event_redraw(rays[hit[kept[j]]].ray, rng);
        march_wavefront(model, query, more, WaveMode::event);
        for (size_t j = 0; j < kept.size(); ++j) {
            const size_t h = kept[j], i = hit[h];
            out.position.push_back(at[h]);
            out.wo.push_back(wo[h]);
            out.target.push_back(target[i]);
            out.image.push_back(image[i]);
            out.footprint.push_back(
                pixel_footprint(data.cameras[image[i]], w2m, at[h], pixel[i][0], pixel[i][1]));
            out.donor.push_back(uint32_t(donor[h]));
            out.draw.push_back(at[h]);
            for (size_t m = 0; m + 1 < draws; ++m) {
                const WaveRay& r = more[j * (draws - 1) + m];
                out.draw.push_back(r.has_event ? r.event_position : at[h]);
            }
        }
        added += kept.size();
        barren = kept.empty() ? barren + 1 : 0;
    }
}

}  // namespace

PixelFootprint pixel_footprint(const Camera& camera, const Mat4& w2m, Vec3 p, float px, float py) {
    const Mat4& c2w = camera.camera_to_world;
    const auto axis = [&](Vec3 a) { return w2m.transform_vector(c2w.transform_vector(a)); };
    const Vec3 origin = w2m.transform_point(c2w.transform_point(Vec3(0.0f, 0.0f, 0.0f)));
    const Vec3 forward = axis(Vec3(0.0f, 0.0f, -1.0f));
    const float depth = dot(p - origin, forward) / dot(forward, forward);  // the camera's z
    PixelFootprint f;
    f.u = axis(Vec3(1.0f, 0.0f, 0.0f)) * (depth / camera.fx);
    f.v = axis(Vec3(0.0f, -1.0f, 0.0f)) * (depth / camera.fy);
    f.corner = -(f.u * (px - std::floor(px)) + f.v * (py - std::floor(py)));
    return f;
}

RelightSamples gather_relight_samples(const NerfModel& model, const Dataset& data, FieldQuery& query,
                                      const RelightSampleSettings& settings,
                                      const RelightProgressFn& progress) {
    if (data.cameras.empty()) throw Error("the relight stage needs training images; the data set has none");
    if (settings.points < 1 || settings.directions < 1 || settings.event_draws < 1)
        throw Error("relight: points, directions and event draws must be at least 1");
    if ((settings.borrowing_pixels > 0 || settings.pooled_neighbours > 0) && !(settings.borrow_radius > 0.0f))
        throw Error("relight: borrowing pixels and pooled neighbours need a positive radius");
    if (settings.borrowing_pixels < 0 || settings.pooled_neighbours < 0)
        throw Error("relight: borrowing pixels and pooled neighbours cannot be negative");
    if (uint64_t(settings.points) * uint64_t(settings.directions) >= (uint64_t(1) << 32))
        throw Error("relight: points x directions must stay under 2^32");
    const size_t n_points = size_t(settings.points);
    const int K = settings.directions;
    const Mat4& w2m = model.world_to_model;
    const uint8_t min_alpha = uint8_t(std::lround(std::clamp(settings.min_alpha, 0.0f, 1.0f) * 255.0f));
    std::vector<Point> points(n_points);
    std::vector<Pcg32> rngs(n_points);
    for (size_t s = 0; s < n_points; ++s) rngs[s] = Pcg32(mix64(settings.seed ^ 0x72656c69676874ULL), s);

    // 1. Events: a camera ray through a random opaque pixel per point, its event drawn from the volume
    // weights; points whose ray found nothing try another pixel, up to k_tries_per_point times.
    std::vector<size_t> todo(n_points);
    for (size_t s = 0; s < n_points; ++s) todo[s] = s;
    for (int attempt = 0; attempt < k_tries_per_point && !todo.empty(); ++attempt) {
        std::vector<WaveRay> rays;
        std::vector<size_t> owner;
        std::vector<Point> pending;
        for (size_t s : todo) {
            const std::optional<PixelDraw> d = draw_opaque_pixel(rngs[s], data, w2m, min_alpha);
            if (!d) continue;
            rays.push_back(d->ray);
            owner.push_back(s);
            Point p;
            p.image = d->image;
            p.pixel = PixelRef{d->image, d->px, d->py, d->ray.jitter};
            p.wo = -d->ray.ray.d;
            p.ray = d->ray.ray;
            p.target = d->target;
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
        const std::vector<Vec3> fallback =
            density_normals(query, missing_at, missing_toward, settings.normal_step);
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
    out.footprint.resize(n);
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
        out.footprint[j] = pixel_footprint(data.cameras[p.image], w2m, p.position, p.pixel.px, p.pixel.py);
    }
    draw_more_events(model, query, points, found, rngs, settings.event_draws, out);
    out.normal = smooth_normals(out.position, out.normal, settings.normal_smoothing);
    for (size_t j = 0; j < n; ++j)  // smoothing may turn a normal past the horizon of its own view
        if (dot(out.normal[j], out.wo[j]) < 0.0f) out.normal[j] = points[found[j]].normal;
    const float min_step = model.march_params().min_step;
    // Whole points' directions, as many per call as the query asks for (a GPU marches a million rays at once;
    // each call's rounds cost a few transfers and a synchronisation whatever their size). A ray's result does not
    // depend on its batch.
    const size_t points_per_round = std::max<size_t>(1, query.batch_rays() / size_t(K));
    for (size_t begin = 0; begin < n; begin += points_per_round) {
        const size_t end = std::min(n, begin + points_per_round);
        std::vector<WaveRay> rays((end - begin) * K);
        tbb::parallel_for(begin, end, [&](size_t j) {
            Pcg32& rng = rngs[found[j]];
            const Frame frame = Frame::from_z(out.normal[j]);
            const float turn = rng.next_float();
            // Pooled points share their directions: each then draws its own elevations within the strata
            // (alone, the strata's midpoints are the better estimate).
            const float shift = settings.pooled_neighbours > 0 ? rng.next_float() : 0.5f;
            const Vec3 origin = relit_spawn_point(out.position[j], out.normal[j], min_step);
            for (int k = 0; k < K; ++k) {
                const float z = 1.0f - (float(k) + shift) / float(K);
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
    out.lit = out.size();
    if (settings.pooled_neighbours > 0) pool_neighbours(settings, out);
    if (settings.borrowing_pixels > 0) add_borrowing_pixels(model, data, query, settings, min_alpha, out);
    return out;
}

}  // namespace npt::nerf
