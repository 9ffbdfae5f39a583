// A relit NeRF as a scattering medium (media/relit_free_flight.h, media/relit_event.h, relit_scatter in
// render/path_integrator.h), driven with analytic fields and with a relightable NerfModel made in code.
// Tolerances: Monte Carlo means within 4 standard errors estimated from the samples themselves, plus the
// integrator's documented deterministic cut-offs where they apply (named at each check).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "core/srgb.h"
#include "media/volume_integrator.h"
#include "media/volume_set.h"
#include "nerf/model_file.h"
#include "relit_test_fields.h"
#include "render/cpu/embree_scene.h"
#include "render/scene_data.h"
#include "test_support.h"

namespace npt {
namespace {

struct Stats {
    double sum = 0, sum2 = 0;
    size_t n = 0;
    void add(double x) {
        sum += x;
        sum2 += x * x;
        ++n;
    }
    double mean() const { return sum / double(n); }
    double se() const { return std::sqrt(std::max(0.0, sum2 / double(n) - mean() * mean()) / double(n)); }
};

// A non-uniform, rotated placement: normals must go through the inverse transpose.
Mat4 skewed_placement() {
    return Mat4::translation(0.1, -0.2, 0.3) * Mat4::rotation_quat(0.2, 0.1, 0.3, 0.9) * Mat4::scale(0.7, 0.45, 0.6);
}

// A ray from a point on a sphere of radius 3 around `centre` towards a random point within `spread` of it.
Ray random_ray_at(std::mt19937& g, Vec3 centre, float spread) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    Vec3 o;
    do o = Vec3(u(g), u(g), u(g));
    while (length(o) > 1.0f || length(o) < 0.1f);
    const Vec3 origin = centre + normalize(o) * 3.0f;
    const Vec3 target = centre + Vec3(u(g), u(g), u(g)) * spread;
    return Ray{origin, normalize(target - origin)};
}

Vec3 world_point(const Mat4& local_to_world, const media::VolumeView& v, Vec3 model) {
    return local_to_world.transform_point(v.nerf.local_to_model.inverse_point(model));
}

// (a) White furnace. The dielectric Principled BSDF (F0 0.04) with base colour 1 does not conserve energy: its
// albedo is 0.97-1.0 at normal incidence but falls at grazing angles (0.61 at cos 0.05 for roughness 0.3, 0.28
// for roughness 1; measured by direct integration of bsdf_eval), so a furnace is not 1 everywhere. What holds
// exactly for any BSDF: with environment radiance 1, 1 - L(x, wo) = E[sum over the path's events of
// throughput x (1 - albedo(wo_k))], the energy the BSDF absorbs along a BSDF-sampled walk. The test estimates
// that sum with an independent BSDF sample per event (unbiased) and checks L + absorbed = 1 for every density
// (thin to opaque), channel 0, within 4 standard errors of the per-path values, plus 2e-4 for shadow rays whose
// transmittance below 1e-4 counts as 0 (a bias of at most 1e-4 per light sample, with MIS weights < 1).
TEST(RelitMedium, WhiteFurnaceBalancesEmissionAndAbsorptionAtAnyDensity) {
    scene::Scene s;
    s.environment.color = Rgb(1.0f);
    render::SceneData data(s, 8, 8);
    const Mat4 place = skewed_placement();
    const media::VolumeView v = test::analytic_view(place);
    render::PathSettings ps;
    ps.max_depth = 1000;  // no truncation: roulette alone ends the paths
    std::mt19937 g(7);
    Pcg32 rng(11, 3), loss(12, 5);
    for (float sigma : {0.5f, 5.0f, 50.0f, 5000.0f}) {
        for (float roughness : {0.3f, 1.0f}) {
            test::BallsField f;
            f.sigma = sigma;
            f.roughness = roughness;
            Stats total, lit;
            for (int i = 0; i < 3000; ++i) {
                const Ray ray = random_ray_at(g, world_point(place, v, f.centre[0]), 0.3f);
                Rgb absorbed;
                const Rgb l = test::trace_relit(data.view(), v, f, ray, rng, ps, &loss, &absorbed);
                total.add(double(l.x) + double(absorbed.x));
                lit.add(l.x);
            }
            EXPECT_NEAR(total.mean(), 1.0, 4.0 * total.se() + 2e-4) << "sigma " << sigma << " roughness " << roughness;
            EXPECT_LE(lit.mean(), 1.0 + 4.0 * lit.se()) << "no energy gained";
            std::printf("sigma %g roughness %g: L %.4f +- %.4f, L + absorbed %.4f +- %.4f\n", sigma, roughness,
                        lit.mean(), lit.se(), total.mean(), total.se());
            if (roughness == 1.0f && sigma >= 5.0f) {
                EXPECT_LT(lit.mean() + 4.0 * lit.se(), 1.0) << "rough and not thin: the BSDF's losses must show";
            }
        }
    }
}

// The analytic value for (b): the world ellipsoid {x : |M x - c| < r} (M the world -> model map) is found
// along the ray in double precision, its normal by central differences of |M x - c|^2 in world space (not the
// renderer's inverse transpose), and the direct light is E f(wo, wi) cos(wi).
struct Ellipsoid {
    Mat4 world_to_model;
    Vec3 centre;
    float radius;
    double implicit(const Vec3& x) const {
        const Vec3 m = world_to_model.transform_point(x) - centre;
        return double(dot(m, m)) - double(radius) * radius;
    }
    bool entry(const Ray& ray, float* t) const {  // bisection on the implicit function along the ray
        float a = 0.0f, step = 1e-3f, b = -1.0f;
        for (float s = 0.0f; s < 10.0f; s += step)
            if (implicit(ray.at(s)) < 0.0) {
                b = s;
                break;
            } else {
                a = s;
            }
        if (b < 0.0f) return false;
        for (int i = 0; i < 40; ++i) {
            const float m = 0.5f * (a + b);
            (implicit(ray.at(m)) < 0.0 ? b : a) = m;
        }
        *t = b;
        return true;
    }
    Vec3 normal(Vec3 x) const {
        const float h = 1e-3f;
        Vec3 n;
        for (int a = 0; a < 3; ++a) {
            Vec3 d(0.0f);
            d[a] = h;
            n[a] = float((implicit(x + d) - implicit(x - d)) / (2.0 * h));
        }
        return normalize(n);
    }
};

float direct_light(const Ellipsoid& e, const Vec3& x, const Ray& ray, const test::BallsField& f, Vec3 to_light,
                   float irradiance) {
    Vec3 n = e.normal(x);
    if (dot(n, ray.d) > 0.0f) n = -n;
    const Frame frame = Frame::from_z(n);
    nerf::IntrinsicSample s;
    s.albedo = f.albedo;
    s.roughness = f.roughness;
    const Vec3 wi = frame.to_local(to_light);
    return materials::bsdf_eval(nerf::intrinsic_bsdf(s), frame.to_local(-ray.d), wi).x * std::fabs(wi.z) * irradiance;
}

// (b) A dense ball (an ellipsoid in the world: the cube is scaled non-uniformly) of Lambert-like albedo 0.6 and
// roughness 1 under a sun, direct light only (max depth 1). sigma 20000 per model unit puts the event within
// the first samples inside (P(beyond the third) = e^-3x34), where the value is the analytic one at a point
// between the entry and three march steps deeper: it must lie within the range of the analytic values there
// (+-2e-3 relative: the finite-difference normal and float rounding). A second, smaller ball between the sun
// and part of the big one must shadow it (the shadow ray's NeRF transmittance), and points facing away from
// the sun get nothing.
TEST(RelitMedium, DenseBallUnderTheSunMatchesTheAnalyticDirectLightAndShadows) {
    scene::Scene s;
    scene::PunctualLight sun;
    sun.type = scene::PunctualType::Directional;
    const Vec3 travel = normalize(Vec3(-0.3f, -1.0f, 0.2f));
    sun.direction = travel;
    sun.intensity = Rgb(3.0f);
    s.lights = {sun};
    render::SceneData data(s, 8, 8);
    const Mat4 place = skewed_placement();
    const media::VolumeView v = test::analytic_view(place);
    test::BallsField f;
    f.sigma = 20000.0f;
    f.albedo = Rgb(0.6f);
    f.roughness = 1.0f;
    f.centre[0] = Vec3(0.5f, 0.45f, 0.5f);
    f.radius[0] = 0.25f;
    // The blocker: along the sun's direction (in model space) from a point on the big ball's lit side.
    const Mat4 world_to_model = place.inverse();  // world -> local, despite the name; local -> model below
    const Vec3 big_world = world_point(place, v, f.centre[0]);
    const Vec3 blocker_world = big_world - travel * 0.7f + Vec3(0.05f, 0.0f, 0.0f);
    f.centre[1] = v.nerf.local_to_model.point(world_to_model.transform_point(blocker_world));
    f.radius[1] = 0.1f;
    f.count = 2;

    const nerf::LocalToModel& l2m = v.nerf.local_to_model;
    // world -> model as a Mat4: local -> model is L local + offset.
    Mat4 l2m_mat;
    for (int r = 0; r < 3; ++r)
        l2m_mat.m[size_t(r)] = {l2m.row[r].x, l2m.row[r].y, l2m.row[r].z, l2m.offset[r]};
    const Mat4 world_to_model_mat = l2m_mat * world_to_model;
    const Ellipsoid big{world_to_model_mat, f.centre[0], f.radius[0]};
    const Ellipsoid blocker{world_to_model_mat, f.centre[1], f.radius[1]};
    // How many of five sun rays (from x and from x moved 0.01 sideways four ways) the blocker stops: 5 is the
    // umbra's inside, 0 full sun, anything else its rim (skipped: a shadow ray starts from the spawn point).
    const Frame sun_frame = Frame::from_z(-travel);
    auto blocked = [&](Vec3 x) {
        int n = 0;
        float t;
        for (Vec3 d : {Vec3(0.0f), sun_frame.s, -sun_frame.s, sun_frame.t, -sun_frame.t})
            n += blocker.entry(Ray{x + d * 0.01f, -travel}, &t) ? 1 : 0;
        return n;
    };

    render::PathSettings ps;
    ps.max_depth = 1;
    std::mt19937 g(5);
    Pcg32 rng(3, 9);
    int lit = 0, shadowed = 0, dark = 0;
    for (int i = 0; i < 400; ++i) {
        const Ray ray = random_ray_at(g, big_world, 0.2f);
        float t0, t_blocker;
        if (!big.entry(ray, &t0)) continue;
        if (blocker.entry(ray, &t_blocker) && t_blocker < t0) continue;  // the blocker is seen first
        // World distance per model march step along this ray.
        const float world_step = v.nerf.march.min_step / length(world_to_model_mat.transform_vector(ray.d));
        float lo = INFINITY, hi = -INFINITY;
        for (int k = 0; k <= 3; ++k) {
            const float e = direct_light(big, ray.at(t0 + float(k) * world_step), ray, f, -travel, 3.0f);
            lo = std::min(lo, e);
            hi = std::max(hi, e);
        }
        const int stopped = blocked(ray.at(t0));
        for (int rep = 0; rep < 3; ++rep) {
            const float l = test::trace_relit(data.view(), v, f, ray, rng, ps).x;
            if (hi <= 0.0f) {
                EXPECT_EQ(l, 0.0f) << "facing away from the sun";
                ++dark;
            } else if (stopped == 5) {
                EXPECT_LT(l, 1e-3f * hi) << "in the blocker's shadow";
                ++shadowed;
            } else if (stopped == 0) {
                EXPECT_GE(l, lo * (1.0f - 2e-3f) - 1e-6f) << "ray " << i;
                EXPECT_LE(l, hi * (1.0f + 2e-3f) + 1e-6f) << "ray " << i;
                ++lit;
            }
        }
    }
    std::printf("lit %d, in the shadow %d, facing away %d\n", lit, shadowed, dark);
    EXPECT_GT(lit, 200);
    EXPECT_GT(dark, 30);
    EXPECT_GT(shadowed, 3);
}

// (c) The free flight's events against the emissive quadrature, on a NeRF with random features: for one ray and
// lattice offset xi, the event lands in step i with probability T_i (1 - exp(-sigma_i dt_i)), so returning the
// NeRF's own colour at the event estimates exactly what march_nerf adds up as emission (up to its cut-off at
// T < 1e-4: at most 1e-4 of the colour, < 1). Per (ray, xi) pair the events of 32 stratified u give one value;
// the pairs' differences from the emissive result must average to 0 within 4 standard errors (+1e-4).
TEST(RelitMedium, EventsReproduceTheEmissiveQuadrature) {
    std::mt19937 g(3);
    nerf::NerfModel model = test::random_relightable_model(21);
    std::vector<float> occ(model.occupancy.cell_count());
    std::uniform_real_distribution<float> u01(0.0f, 1.0f);
    for (float& o : occ) o = u01(g) < 0.6f ? 1.0f : 0.0f;
    model.occupancy.set_density(occ, 0.5f);
    media::VolumeView v;
    media::VolumeDesc desc;
    desc.file = "random.npt";
    media::fill_nerf_volume(model, desc, Vec3(-1.0f), Vec3(1.0f), "test", v);
    v.world_to_local = media::affine_from(skewed_placement().inverse());
    v.density_scale = 0.6f;
    ASSERT_TRUE(v.nerf.relit);
    const media::RelitNerfField field = media::relit_field(v);
    const Vec3 centre = world_point(skewed_placement(), v, Vec3(0.5f));
    Stats diff[3], hit_diff;
    for (int pair = 0; pair < 200; ++pair) {
        const Ray ray = random_ray_at(g, centre, 0.3f);
        const float xi = u01(g);
        float ta, tb;
        if (!media::intersect_box(v.world_to_local.apply(ray.o), v.world_to_local.apply_vector(ray.d), v.local_min,
                                  v.local_max, 0.0f, INFINITY, &ta, &tb))
            continue;
        media::Accumulator acc;
        media::march_nerf(v, ray, ta, tb, xi, acc);
        Ray mray;
        float tmax;
        ASSERT_TRUE(media::nerf_model_segment(v, ray, ta, tb, &mray, &tmax));
        const int m = 32;
        const float shift = u01(g);
        Rgb sum(0.0f);
        float hits = 0.0f;
        for (int k = 0; k < m; ++k) {
            media::FreeFlight f;
            f.target = media::free_flight_target((float(k) + shift) / float(m));
            media::march_relit(v, field, ray, ta, tb, xi, f);
            if (!f.event) continue;
            float sigma;
            Rgb srgb;
            v.nerf.field.query(f.p_model, mray.d, &sigma, &srgb);
            sum += Rgb(srgb_to_linear(srgb.x), srgb_to_linear(srgb.y), srgb_to_linear(srgb.z));
            hits += 1.0f;
        }
        for (int c = 0; c < 3; ++c) diff[c].add(double(sum[c]) / m - double(acc.radiance[c]));
        // With colour 1 the emissive result is 1 - T.
        media::Accumulator ones;
        ones.with_emission = false;
        media::march_nerf(v, ray, ta, tb, xi, ones);
        hit_diff.add(double(hits) / m - (1.0 - (ones.done() ? 0.0 : std::exp(double(ones.log_t)))));
    }
    ASSERT_GT(hit_diff.n, 150u);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(diff[c].mean(), 0.0, 4.0 * diff[c].se() + 1e-4) << "channel " << c;
    EXPECT_NEAR(hit_diff.mean(), 0.0, 4.0 * hit_diff.se() + 1e-4);
    EXPECT_GT(hit_diff.se(), 0.0) << "the events must vary with u";
}

// The spawn point and the world normal of an event under a non-uniform placement.
TEST(RelitMedium, EventNormalIsTheInverseTransposeAndFacesTheRay) {
    const Mat4 place = skewed_placement();
    const media::VolumeView v = test::analytic_view(place);
    const Ray ray{Vec3(0.3f, 2.0f, -1.0f), normalize(Vec3(-0.1f, -1.0f, 0.5f))};
    nerf::IntrinsicSample s;
    s.normal = normalize(Vec3(0.3f, -0.8f, 0.5f));
    const Vec3 p_model(0.4f, 0.5f, 0.6f);
    const media::RelitEvent e = media::make_relit_event(v, ray, 1.0f, p_model, s);
    // A world tangent t (dot(n_world, t) = 0) maps to a model tangent: dot(n_model, A t) = 0.
    const Mat4 world_to_local = place.inverse();
    auto to_model_vec = [&](Vec3 w) { return v.nerf.local_to_model.vector(world_to_local.transform_vector(w)); };
    EXPECT_NEAR(dot(e.sample.normal, to_model_vec(e.frame.s)), 0.0f, 1e-5f);
    EXPECT_NEAR(dot(e.sample.normal, to_model_vec(e.frame.t)), 0.0f, 1e-5f);
    EXPECT_LT(dot(e.frame.n, ray.d), 0.0f) << "faces the ray's origin";
    EXPECT_NEAR(length(e.frame.n), 1.0f, 1e-5f);
    // The spawn point is the model point moved by the offset along the facing model normal.
    const Vec3 origin_model = v.nerf.local_to_model.point(world_to_local.transform_point(e.origin));
    const Vec3 event_model = v.nerf.local_to_model.point(world_to_local.transform_point(e.p));
    test::expect_near(origin_model - event_model,
                      e.sample.normal * (nerf::k_relit_spawn_offset_steps * v.nerf.march.min_step), 1e-5f);
    EXPECT_GT(dot(e.origin - e.p, e.frame.n), 0.0f);
}

// A relightable NerfModel made in code, placed by the volume loading's own code (fill_nerf_volume) and rendered
// by trace_path on the CPU backend.
struct ModelScene {
    nerf::NerfModel model = test::random_relightable_model(5);
    media::VolumeView view;
    explicit ModelScene(const std::string& extras) {
        const media::VolumeDesc d = media::parse_volume_desc(extras, "scene.gltf: node 'nerf'");
        media::fill_nerf_volume(model, d, Vec3(-1.0f), Vec3(1.0f), "scene.gltf: node 'nerf'", view);
        view.world_to_local = media::affine_from(skewed_placement().inverse());
    }
};

Stats render_model(const scene::Scene& s, const media::VolumeView& view, int paths, uint64_t seed) {
    render::SceneData data(s, 8, 8);
    render::SceneView sv = data.view();
    sv.volumes = Span<const media::VolumeView>{&view, 1};
    render::cpu::EmbreeScene embree(s);
    render::cpu::EmbreeTracer tracer(embree);
    std::mt19937 g{uint32_t(seed)};
    Pcg32 rng(seed, 1);
    render::PathSettings ps;
    const Vec3 centre = world_point(skewed_placement(), view, Vec3(0.5f));
    Stats st;
    for (int i = 0; i < paths; ++i) st.add(render::trace_path(sv, tracer, random_ray_at(g, centre, 0.3f), rng, ps).x);
    return st;
}

TEST(RelitMedium, RelightableModelIsRelitByDefaultAndEmitsNothing) {
    ModelScene relit(R"({"volume": {"file": "m.npt"}})");
    ASSERT_TRUE(relit.view.nerf.relit);
    ASSERT_TRUE(relit.view.nerf.intrinsic.valid());
    ModelScene emissive(R"({"volume": {"file": "m.npt", "shading": "emissive"}})");
    ASSERT_FALSE(emissive.view.nerf.relit);
    // No light at all: the relit model is black, the emissive one glows.
    const scene::Scene dark;
    const Stats r = render_model(dark, relit.view, 200, 1);
    EXPECT_EQ(r.sum, 0.0);
    EXPECT_GT(render_model(dark, emissive.view, 200, 1).mean(), 1e-3);
    // Under a uniform environment of 1: the renderer's estimate equals the analytic-field harness's on the same
    // field (different random numbers: within 4 combined standard errors) and gains no energy.
    scene::Scene lit;
    lit.environment.color = Rgb(1.0f);
    const Stats a = render_model(lit, relit.view, 1500, 2);
    render::SceneData data(lit, 8, 8);
    std::mt19937 g(9);
    Pcg32 rng(9, 4);
    render::PathSettings ps;
    Stats b;
    const Vec3 centre = world_point(skewed_placement(), relit.view, Vec3(0.5f));
    for (int i = 0; i < 1500; ++i)
        b.add(test::trace_relit(data.view(), relit.view, media::relit_field(relit.view), random_ray_at(g, centre, 0.3f),
                                rng, ps)
                  .x);
    EXPECT_NEAR(a.mean(), b.mean(), 4.0 * std::sqrt(a.se() * a.se() + b.se() * b.se()));
    EXPECT_LE(a.mean(), 1.0 + 4.0 * a.se());
    EXPECT_LT(a.mean(), 0.999) << "the model must absorb something (its albedo is below 1)";
}

TEST(RelitMedium, ShadingFieldBadInput) {
    const std::string where = "scene.gltf: node 'nerf'";
    for (const char* bad : {R"("shading": 3)", R"("shading": "glossy")", R"("shading": "")", R"("shading": null)"})
        test::expect_error_message(
            [&] { media::parse_volume_desc(std::string(R"({"volume": {"file": "m.npt", )") + bad + "}}", where); },
            {where, "extras.volume.shading", "relit", "emissive"});
    // "relit" on a model without a relight section: the file and the field named, one line.
    const nerf::NerfModel plain = test::random_relightable_model(5, false);
    media::VolumeView v;
    const media::VolumeDesc d = media::parse_volume_desc(R"({"volume": {"file": "plain.npt", "shading": "relit"}})", where);
    test::expect_error_message([&] { media::fill_nerf_volume(plain, d, Vec3(-1.0f), Vec3(1.0f), where, v); },
                               {where, "extras.volume.shading", "plain.npt", "relightable"});
    // Through a scene and a saved model file; and on a grid.
    const auto dir = test::temp_dir();
    nerf::save_model(dir / "plain.npt", plain, false);
    scene::Scene s;
    s.source = dir / "scene.gltf";
    scene::VolumeInstance inst;
    inst.name = "nerf";
    inst.local_to_world = Mat4::identity();
    inst.declared_in = s.source;
    inst.extras_json = R"({"volume": {"file": "plain.npt", "shading": "relit"}})";
    s.volumes = {inst};
    test::expect_error_message([&] { media::VolumeSet set(s); }, {"scene.gltf", "extras.volume.shading", "plain.npt"});
    s.volumes[0].extras_json = R"({"volume": {"file": "cloud.vdb", "shading": "relit"}})";
    test::expect_error_message([&] { media::VolumeSet set(s); }, {"scene.gltf", "extras.volume.shading", "cloud.vdb"});
    // A model that is not relightable renders emissive by default.
    s.volumes[0].extras_json = R"({"volume": {"file": "plain.npt"}})";
    const media::VolumeSet set(s);
    EXPECT_FALSE(set.views()[0].nerf.relit);
}

}  // namespace
}  // namespace npt
