// The relight stage's data: points on the object seen by training pixels, each with what the trained NeRF
// says about its surroundings. One point per training ray, drawn from the ray's volume weights exactly as the
// relit renderer draws its scattering events; at each point the density normal and, for a fixed set of
// directions over its hemisphere, the transmittance toward the environment and the radiance the NeRF sends
// back from that direction (the object's own light under the capture illumination: the indirect light).
// Computed once, before the optimisation, with the wavefront marcher (the field evaluated by `query`: CPU or
// GPU), deterministically for a seed.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "core/vec.h"
#include "nerf/dataset.h"
#include "nerf/nerf_model.h"
#include "nerf/relight/field_query.h"

namespace npt::nerf {

enum class NormalEstimator {
    density,        // -grad(log sigma) at the event (surface_normals.h)
    depth_stencil,  // the expected-depth stencil around the pixel; the density normal where it has none
};

struct RelightSampleSettings {
    int points = 16384;   // surface points (training rays that hit the object)
    int directions = 16;  // light directions per point, stratified over the normal's hemisphere
    NormalEstimator normals = NormalEstimator::depth_stencil;
    float normal_step = 0.004f;      // model units: central-difference step of the density gradient
    float normal_pixels = 2.0f;      // the depth stencil's half width in pixels
    float normal_smoothing = 0.02f;  // model units: radius of smooth_normals over the points (0: off)
    float min_alpha = 0.99f;         // pixels more transparent than this in the image are not used
    // Events drawn per point on its camera ray: the fit queries the intrinsic fields at one of them each time
    // it uses the point. The renderer's events spread over the depth of the surface; fitted at a single draw
    // per ray, the hash grid's fine levels memorise those positions and return noise between them.
    int event_draws = 4;
    // Pixels that supervise the fields without light directions of their own: each borrows the normal, the
    // directions, the visibility and the indirect light of the nearest point within borrow_radius (model
    // units) that faces its camera. The light varies slowly over a surface, the albedo does not: this buys
    // albedo supervision at the cost of one camera ray per pixel instead of `directions` light rays.
    int borrowing_pixels = 0;
    float borrow_radius = 0.02f;
    // Lit points whose light directions each lit point shades with besides its own: the nearest ones within
    // borrow_radius whose normals agree (within ~25 degrees). Shadowing and indirect light vary slowly over a
    // surface, so a point's few directions are a noisy estimate of them that its neighbours' directions
    // average, at no marching cost: the fit's per-point shading target is that much less noisy.
    int pooled_neighbours = 0;
    uint64_t seed = 1;
};

// A training pixel's square around a sample's event, model space: the event is at corner + x u + y v, (x, y)
// where its camera ray crosses the pixel (each in [0, 1)); u and v are one pixel's step right and down at the
// event's depth. The photo's pixel is the object averaged over that square, so the fit can average the fields
// over it too (RelightTrainSettings::footprint_queries) instead of blurring them by it.
struct PixelFootprint {
    Vec3 corner{0.0f, 0.0f, 0.0f}, u{0.0f, 0.0f, 0.0f}, v{0.0f, 0.0f, 0.0f};
};

struct RelightSamples {
    int directions = 0;
    // Per point, model space.
    std::vector<Vec3>
        position;              // the scattering event (shaded: normal, visibility and indirect light are its)
    int draws = 1;             // events drawn per point (settings.event_draws)
    std::vector<Vec3> draw;    // [point * draws + m]: where the fields are queried; m = 0 is `position`
    std::vector<Vec3> wo;      // unit direction toward the camera
    std::vector<Vec3> normal;  // lit points: the surface normal (settings.normals), unit, turned toward wo
    std::vector<Rgb> target;   // the pixel's colour, linear
    std::vector<uint32_t> image;  // training image index
    std::vector<PixelFootprint> footprint;  // the pixel's square, relative to `position`
    // Per point and direction ([point * directions + k]).
    std::vector<Vec3> dir;  // unit, model space
    std::vector<float>
        visibility;             // transmittance through the model from the offset point to the environment
    std::vector<Rgb> indirect;  // linear radiance arriving along -dir from the model itself

    // Samples [0, lit) are points with light of their own; the rest are borrowing pixels
    // (settings.borrowing_pixels), whose light is that of point donor[s - lit]. normal, dir, visibility and
    // indirect hold the lit points' only.
    size_t lit = 0;
    std::vector<uint32_t> donor;
    // Per lit point, the lit points whose directions it pools (settings.pooled_neighbours):
    // [point * neighbours + m], k_no_neighbour where it found fewer.
    static constexpr uint32_t k_no_neighbour = 0xffffffffu;
    int neighbours = 0;
    std::vector<uint32_t> neighbour;

    size_t size() const { return position.size(); }
    // The point whose normal and light sample s uses.
    uint32_t light_of(size_t s) const { return s < lit || donor.empty() ? uint32_t(s) : donor[s - lit]; }
    // The light directions point L is shaded with ([point * directions + k] indices): its own, then its
    // pooled neighbours'.
    void light_directions(uint32_t L, std::vector<uint32_t>& out) const {
        out.clear();
        const uint32_t K = uint32_t(directions);
        for (uint32_t k = 0; k < K; ++k) out.push_back(L * K + k);
        for (int m = 0; m < neighbours && !neighbour.empty(); ++m) {
            const uint32_t q = neighbour[size_t(L) * size_t(neighbours) + size_t(m)];
            if (q == k_no_neighbour) break;
            for (uint32_t k = 0; k < K; ++k) out.push_back(q * K + k);
        }
    }
    // Draw m (taken modulo draws) of point s; `position` when the samples carry no draws.
    Vec3 draw_position(size_t s, uint32_t m) const {
        return draws > 1 && draw.size() == position.size() * size_t(draws)
                   ? draw[s * size_t(draws) + m % uint32_t(draws)]
                   : position[s];
    }
};

// The square of pixel (px, py) (continuous pixel coordinates) of `camera` at the model-space point p, which
// its ray meets: a pinhole's (the lens's distortion changes it by far less than a pixel).
PixelFootprint pixel_footprint(const Camera& camera, const Mat4& world_to_model, Vec3 p, float px, float py);

// Called with (points done, points wanted); from worker threads, never two calls at once.
using RelightProgressFn = std::function<void(size_t, size_t)>;

// Throws npt::Error when the model sees (almost) nothing of the object: fewer than 1% of the points found.
RelightSamples gather_relight_samples(const NerfModel& model, const Dataset& data, FieldQuery& query,
                                      const RelightSampleSettings& settings,
                                      const RelightProgressFn& progress = {});

}  // namespace npt::nerf
