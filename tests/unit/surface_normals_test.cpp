// The relight stage's surface normals (nerf/relight/surface_normals.h) on an analytic field: a ball of constant
// density with a thin soft shell (a NeRF-like surface layer), whose true normal is known everywhere. The
// depth-stencil normal must agree with it to a fraction of a degree inside the silhouette and report none at the
// silhouette's edge; the density normal agrees where the field is smooth.
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "nerf/relight/surface_normals.h"
#include "test_support.h"

namespace npt::nerf {
namespace {

constexpr float k_pi = 3.14159265358979f;
const Vec3 k_centre(0.5f, 0.5f, 0.5f);
constexpr float k_radius = 0.2f;

// sigma = 400 per model unit inside the ball, falling off smoothly over a 0.01 shell.
class BallQuery : public FieldQuery {
  public:
    void evaluate(const Vec3* positions, const Vec3*, size_t n, float* sigma, Rgb* rgb) override {
        for (size_t i = 0; i < n; ++i) {
            const float r = length(positions[i] - k_centre);
            sigma[i] = 400.0f / (1.0f + std::exp((r - k_radius) / 0.002f));
            if (rgb) rgb[i] = Rgb(0.5f);
        }
    }
};

NerfModel ball_model() {
    NerfModel m;
    m.config.encoding.grid.levels = 2;
    m.config.encoding.grid.log2_table_size = 10;
    m.config.occupancy.resolution = 16;
    m.aabb_scale = 1.0f;
    m.world_to_model = ngp_world_to_model(0.33f, Vec3(0.5f));
    m.occupancy = OccupancyGrid(1, 16);  // every cell occupied: the march samples everywhere
    return m;
}

// A camera 1.5 world units from the ball (model 0.5 after ngp's 0.33 scale) looking at its centre.
Camera front_camera() {
    Camera c;
    c.width = c.height = 64;
    c.fx = c.fy = 40.0f;  // the ball spans about 35 of the 64 pixels
    c.cx = c.cy = 32.0f;
    // NeRF-synthetic world: model = world * 0.33 + 0.5 with axes permuted; look along -Z of the camera from +Z.
    c.camera_to_world = Mat4::identity();
    c.camera_to_world.m[2][3] = 1.5f;
    return c;
}

float angle_deg(Vec3 a, Vec3 b) { return std::acos(std::clamp(dot(a, b), -1.0f, 1.0f)) * 180.0f / k_pi; }

TEST(SurfaceNormals, DepthStencilFollowsTheBallAndDropsItsEdge) {
    const NerfModel m = ball_model();
    BallQuery query;
    const std::vector<Camera> cams{front_camera()};
    const Mat4& w2m = m.world_to_model;
    std::vector<PixelRef> pixels;
    Pcg32 rng(1, 2);
    for (int y = 0; y < 64; y += 3)
        for (int x = 0; x < 64; x += 3) pixels.push_back(PixelRef{0, x + 0.5f, y + 0.5f, rng.next_float()});
    const std::vector<Vec3> n = depth_stencil_normals(m, query, cams, pixels, 3.0f);
    int inside = 0, found = 0, edge_found = 0, edge = 0;
    double worst = 0, sum = 0;
    for (size_t i = 0; i < pixels.size(); ++i) {
        const Ray world = generate_pixel_ray(cams[0], pixels[i].px, pixels[i].py);
        const Ray ray{w2m.transform_point(world.o), normalize(w2m.transform_vector(world.d))};
        // The ray's first crossing of the sphere r = k_radius (model space), if any.
        const Vec3 oc = ray.o - k_centre;
        const float b = dot(oc, ray.d), c = dot(oc, oc) - k_radius * k_radius, disc = b * b - c;
        const bool hits = disc > 0.0f;
        const float impact = hits ? std::sqrt(std::max(0.0f, k_radius * k_radius - disc)) / k_radius : 2.0f;  // closest approach / radius
        const bool has = dot(n[i], n[i]) > 0.0f;
        if (hits && impact < 0.8f) {  // well inside the silhouette
            ++inside;
            if (!has) continue;
            ++found;
            const Vec3 truth = normalize(ray.o + ray.d * (-b - std::sqrt(disc)) - k_centre);
            const double err = angle_deg(n[i], truth);
            worst = std::max(worst, err);
            sum += err;
        } else if (!hits) {
            ++edge;
            edge_found += has;
        }
    }
    ASSERT_GT(inside, 40);
    EXPECT_EQ(found, inside) << "the stencil found no surface inside the silhouette";
    // The expected depth lies on the sphere up to the march's quadrature (samples ~0.002 apart, as wide as the
    // shell), which differs a little between the stencil's rays; over a 6-pixel stencil (0.04 model units) that
    // tilts the normal by a fraction of a degree (measured: mean 0.4, worst 1.2; mean 1.0 with a 0.5-pixel
    // half width, where the quadrature dominates). The density normal scatters by tens of degrees on a real NeRF.
    EXPECT_LT(sum / found, 0.5);
    EXPECT_LT(worst, 2.0);
    EXPECT_EQ(edge_found, 0) << "normals reported for rays that miss the ball";
    EXPECT_GT(edge, 0);
}

TEST(SurfaceNormals, DensityNormalIsTheRadialDirection) {
    BallQuery query;
    std::vector<Vec3> at, toward;
    Pcg32 rng(3, 4);
    for (int i = 0; i < 50; ++i) {
        const float z = 2.0f * rng.next_float() - 1.0f, phi = 2.0f * k_pi * rng.next_float();
        const float s = std::sqrt(1.0f - z * z);
        const Vec3 dir(s * std::cos(phi), s * std::sin(phi), z);
        at.push_back(k_centre + dir * (k_radius + 0.001f * (rng.next_float() - 0.5f)));
        toward.push_back(i % 2 ? dir : -dir);  // turned toward whichever side asks
    }
    const std::vector<Vec3> n = density_normals(query, at, toward, 0.002f);
    for (size_t i = 0; i < at.size(); ++i) {
        const Vec3 radial = normalize(at[i] - k_centre);
        const Vec3 truth = dot(radial, toward[i]) < 0.0f ? -radial : radial;
        EXPECT_LT(angle_deg(n[i], truth), 0.5f) << i;
    }
}

// A noisy plane meeting a noisy wall at a right angle (an edge, as a box's or the disk's rim): smoothing must
// bring the plane's normals close to the truth and leave the edge sharp (the faces' normals do not blend).
TEST(SurfaceNormals, SmoothingRemovesBumpsAndKeepsEdges) {
    Pcg32 rng(7, 8);
    std::vector<Vec3> points, normals, truth;
    for (int i = 0; i < 6000; ++i) {
        const bool floor = i % 2 == 0;
        const float u = rng.next_float() * 0.2f, v = rng.next_float() * 0.2f;
        const Vec3 p = floor ? Vec3(u, v, 0.0f) : Vec3(u, 0.0f, v);  // wall: the plane y = 0 above the floor
        const Vec3 t = floor ? Vec3(0, 0, 1) : Vec3(0, 1, 0);
        // Bumps of about 15 degrees.
        const Vec3 noisy = normalize(t + Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f) * 0.5f);
        points.push_back(p);
        normals.push_back(noisy);
        truth.push_back(t);
    }
    normals.push_back(Vec3(0.0f));  // a point without a normal stays without one
    points.push_back(Vec3(0.1f));
    truth.push_back(Vec3(0.0f));
    const std::vector<Vec3> smooth = smooth_normals(points, normals, 0.02f);
    ASSERT_EQ(smooth.size(), normals.size());
    EXPECT_EQ(dot(smooth.back(), smooth.back()), 0.0f);
    double before = 0, after = 0, at_edge = 0;
    int n = 0, edge = 0;
    for (size_t i = 0; i + 1 < points.size(); ++i) {
        before += angle_deg(normals[i], truth[i]);
        after += angle_deg(smooth[i], truth[i]);
        ++n;
        const float to_edge = std::hypot(points[i].y, points[i].z);  // distance to the line y = z = 0
        if (to_edge < 0.005f) {
            at_edge += angle_deg(smooth[i], truth[i]);
            ++edge;
        }
    }
    EXPECT_GT(before / n, 10.0);  // the bumps are there
    EXPECT_LT(after / n, 3.0);    // ~40 neighbours in the radius: noise down by ~6x
    ASSERT_GT(edge, 20);
    // Next to the edge half of each point's neighbours lie on the other face at 90 degrees: weighted by
    // max(0, cos)^4 of a noisy normal they count for little (measured 2.1 deg; a plain Gaussian average tilts
    // them by 37 deg).
    EXPECT_LT(at_edge / edge, 6.0);
    EXPECT_EQ(smooth_normals(points, normals, 0.0f).size(), normals.size());
}

}  // namespace
}  // namespace npt::nerf
