// The relight stage (nerf/relight/): the model file's relight section (round trip, bad input), the intrinsic
// field's per-point query against the batched network the trainer uses, the trainer's gradient against finite
// differences of its objective, and recovery of a known albedo from synthetic surface points.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "core/error.h"
#include "core/rng.h"
#include "materials/bsdf.h"
#include "nerf/mlp_batch.h"
#include "nerf/model_file.h"
#include "nerf/relight/relight_section.h"
#include "core/srgb.h"
#include "nerf/relight/relight_env.h"
#include "nerf/relight/relight_trainer.h"
#include "nerf/relight/wavefront_march.h"
#include "test_support.h"

namespace npt::nerf {
namespace {

namespace fs = std::filesystem;

IntrinsicConfig small_intrinsic() {
    IntrinsicConfig c;
    c.grid = {4, 2, 10, 4, 1.5f};
    c.finest_resolution = 64.0f;
    c.width = 16;
    c.hidden_layers = 1;
    return c;
}

NerfModel small_model() {
    NerfModel m;
    m.config.encoding.grid.levels = 2;
    m.config.encoding.grid.log2_table_size = 10;
    m.config.occupancy.resolution = 16;
    m.aabb_scale = 1.0f;
    m.world_to_model = ngp_world_to_model(0.33f, Vec3(0.5f));
    m.params.assign(m.layout().total, 0.01f);
    m.occupancy = OccupancyGrid(1, 16);
    return m;
}

RelightFields random_fields(float aabb_scale) {
    RelightFields f;
    f.config = small_intrinsic();
    const size_t n = make_intrinsic_layout(f.config, aabb_scale).total;
    Pcg32 rng(3, 4);
    f.params.resize(n);
    for (float& p : f.params) p = rng.next_float() - 0.5f;
    f.capture_env.width = 8;
    f.capture_env.height = 4;
    for (int i = 0; i < 32; ++i) f.capture_env.texels.push_back(Rgb(0.1f * i, 1.0f, 2.0f));
    f.exposure = {Rgb(1.0f), Rgb(0.5f), Rgb(2.0f)};
    f.steps = 12;
    f.seconds = 3.5;
    return f;
}

TEST(RelightSection, RoundTripsThroughTheModelFile) {
    const fs::path dir = test::temp_dir() / "relight_section";
    fs::create_directories(dir);
    NerfModel m = small_model();
    save_model(dir / "plain.npt", m);
    EXPECT_FALSE(load_model(dir / "plain.npt").relightable());
    EXPECT_FALSE(load_model(dir / "plain.npt").intrinsic().valid());

    m.relight = random_fields(m.aabb_scale);
    save_model(dir / "relit.npt", m);
    const NerfModel back = load_model(dir / "relit.npt");
    ASSERT_TRUE(back.relightable());
    const RelightFields& a = *m.relight;
    const RelightFields& b = *back.relight;
    EXPECT_EQ(a.params, b.params);
    EXPECT_EQ(b.capture_env.width, 8);
    EXPECT_EQ(b.capture_env.height, 4);
    EXPECT_EQ(0, std::memcmp(a.capture_env.texels.data(), b.capture_env.texels.data(), 32 * sizeof(Rgb)));
    ASSERT_EQ(b.exposure.size(), 3u);
    EXPECT_EQ(b.exposure[2].x, 2.0f);
    EXPECT_EQ(b.steps, 12u);
    EXPECT_EQ(b.config.width, 16);
    EXPECT_EQ(b.config.diffuse, IntrinsicDiffuse::burley);
    EXPECT_EQ(back.intrinsic().query(Vec3(0.5f)).diffuse, IntrinsicDiffuse::burley);
    // The query sees the same network.
    const Vec3 p(0.3f, 0.6f, 0.45f);
    const IntrinsicSample qa = m.intrinsic().query(p), qb = back.intrinsic().query(p);
    EXPECT_EQ(qa.albedo.x, qb.albedo.x);
    EXPECT_EQ(qa.normal.z, qb.normal.z);
}

TEST(RelightSection, BadPayloadsAreOneLineErrors) {
    const RelightFields f = random_fields(1.0f);
    const std::vector<uint8_t> good = encode_relight_section(f, 1.0f);
    EXPECT_NO_THROW(decode_relight_section(good.data(), good.size(), "m.npt", 1.0f));
    auto fails = [&](std::vector<uint8_t> bytes, const std::string& part) {
        try {
            decode_relight_section(bytes.data(), bytes.size(), "m.npt", 1.0f);
            ADD_FAILURE() << "accepted; expected an error containing '" << part << "'";
        } catch (const Error& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find("m.npt: relight section"), std::string::npos) << msg;
            EXPECT_NE(msg.find(part), std::string::npos) << msg;
            EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
        }
    };
    fails({1, 2, 3}, "truncated");
    fails(std::vector<uint8_t>(good.begin(), good.end() - 4), "arrays need");
    std::vector<uint8_t> extra = good;
    extra.push_back(0);
    fails(extra, "arrays need");
    uint64_t len;
    std::memcpy(&len, good.data(), 8);
    std::vector<uint8_t> huge = good;
    const uint64_t big = uint64_t(1) << 60;
    std::memcpy(huge.data(), &big, 8);
    fails(huge, "past the section's end");
    std::vector<uint8_t> nan = good;
    const float q = std::numeric_limits<float>::quiet_NaN();
    std::memcpy(nan.data() + 8 + len + 4 * 5, &q, 4);
    fails(nan, "parameter 5 is NaN");
    std::vector<uint8_t> neg = good;
    const float m1 = -1.0f;
    std::memcpy(neg.data() + 8 + len + 4 * f.params.size() + 4, &m1, 4);
    fails(neg, "environment texel 0");
    // A header that lies about the network: levels out of range.
    std::string text(reinterpret_cast<const char*>(good.data() + 8), size_t(len));
    const size_t at = text.find("\"levels\":4");
    ASSERT_NE(at, std::string::npos);
    text.replace(at, 10, "\"levels\":99");
    std::vector<uint8_t> bad(8);
    const uint64_t nl = text.size();
    std::memcpy(bad.data(), &nl, 8);
    bad.insert(bad.end(), text.begin(), text.end());
    bad.insert(bad.end(), good.begin() + 8 + len, good.end());
    fails(bad, "'levels' is 99");
}

// The header with its text edited (same payload after it).
std::vector<uint8_t> with_header(const std::vector<uint8_t>& good, const std::string& from, const std::string& to) {
    uint64_t len;
    std::memcpy(&len, good.data(), 8);
    std::string text(reinterpret_cast<const char*>(good.data() + 8), size_t(len));
    const size_t at = text.find(from);
    if (at == std::string::npos) throw std::runtime_error("no '" + from + "' in the header");
    text.replace(at, from.size(), to);
    std::vector<uint8_t> out(8);
    const uint64_t nl = text.size();
    std::memcpy(out.data(), &nl, 8);
    out.insert(out.end(), text.begin(), text.end());
    out.insert(out.end(), good.begin() + 8 + std::ptrdiff_t(len), good.end());
    return out;
}

// The first relightable models' header has no "diffuse": they keep the layered lobe they were fitted with.
TEST(RelightSection, TheDiffuseLobeIsReadAndOldModelsStayLayered) {
    RelightFields f = random_fields(1.0f);
    f.config.diffuse = IntrinsicDiffuse::layered;
    std::vector<uint8_t> bytes = encode_relight_section(f, 1.0f);
    EXPECT_EQ(decode_relight_section(bytes.data(), bytes.size(), "m.npt", 1.0f).config.diffuse,
              IntrinsicDiffuse::layered);
    f.config.diffuse = IntrinsicDiffuse::burley;
    const std::vector<uint8_t> good = encode_relight_section(f, 1.0f);
    EXPECT_EQ(decode_relight_section(good.data(), good.size(), "m.npt", 1.0f).config.diffuse,
              IntrinsicDiffuse::burley);
    bytes = with_header(good, ",\"diffuse\":\"burley\"", "");
    EXPECT_EQ(decode_relight_section(bytes.data(), bytes.size(), "m.npt", 1.0f).config.diffuse,
              IntrinsicDiffuse::layered);
    bytes = with_header(good, "\"diffuse\":\"burley\"", "\"diffuse\":\"lambert\"");
    try {
        decode_relight_section(bytes.data(), bytes.size(), "m.npt", 1.0f);
        ADD_FAILURE() << "accepted an unknown diffuse lobe";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("'diffuse'"), std::string::npos) << e.what();
    }
}

TEST(IntrinsicField, QueryMatchesTheTrainersBatchedNetwork) {
    const RelightFields f = random_fields(2.0f);
    const IntrinsicLayout l = make_intrinsic_layout(f.config, 2.0f);
    const IntrinsicFieldView view(l, f.params.data());
    const Vec3 pts[3] = {Vec3(0.1f, 0.2f, 0.3f), Vec3(0.9f, -0.2f, 1.2f), Vec3(0.5f)};
    const int dims = l.grid.output_dims();
    std::vector<float> enc(3 * dims), out(3 * k_intrinsic_outputs);
    for (int i = 0; i < 3; ++i)
        hash_encode(l.grid, f.params.data() + l.grid_offset, l.grid_position(pts[i]), &enc[i * dims]);
    mlp_forward_batch(l.mlp, f.params.data() + l.mlp_offset, enc.data(), 3, out.data(), nullptr);
    for (int i = 0; i < 3; ++i) {
        const IntrinsicSample a = view.query(pts[i]), b = intrinsic_from_outputs(&out[i * k_intrinsic_outputs]);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(a.albedo[c], b.albedo[c], 1e-5f);
            EXPECT_NEAR(a.normal[c], b.normal[c], 1e-5f);
        }
        EXPECT_NEAR(a.roughness, b.roughness, 1e-5f);
        EXPECT_GE(a.roughness, k_min_roughness);
        EXPECT_NEAR(length(a.normal), 1.0f, 1e-5f);
    }
}

// Synthetic surface points on a sphere of radius 0.2 about the model's centre: normals radial, views in the
// normal's hemisphere, K directions per point with random visibility and indirect light, and targets made by the
// estimator the trainer fits, with a known albedo, roughness 0.5 and a uniform white environment.
// On a sphere every function of the position is one of the normal, and so could be light from that direction:
// the albedo varies faster than an 8x4 environment can (texture against lighting frequency, the assumption every
// decomposition rests on).
Rgb true_albedo(Vec3 p) {
    return Rgb(0.2f + 0.3f * (1.0f + std::sin(40.0f * p.x)), 0.5f, 0.5f + 0.3f * std::sin(30.0f * (p.y + p.z)));
}

RelightSamples synthetic_samples(int points, int K, bool shadows) {
    RelightSamples s;
    s.directions = K;
    Pcg32 rng(11, 12);
    auto unit = [&] {
        const float z = 1.0f - 2.0f * rng.next_float(), phi = 6.2831853f * rng.next_float();
        const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
        return Vec3(r * std::cos(phi), r * std::sin(phi), z);
    };
    for (int i = 0; i < points; ++i) {
        const Vec3 n = unit();
        const Vec3 p = Vec3(0.5f) + n * 0.2f;
        Vec3 wo = unit();
        if (dot(wo, n) < 0.0f) wo = -wo;
        s.position.push_back(p);
        s.normal.push_back(n);
        s.wo.push_back(wo);
        s.image.push_back(uint32_t(i % 2));
        const Frame frame = Frame::from_z(n);
        IntrinsicSample truth;
        truth.albedo = true_albedo(p);
        truth.roughness = 0.5f;
        truth.diffuse = IntrinsicConfig{}.diffuse;  // the fit's lobe (recovery_settings, small_intrinsic)
        const materials::Bsdf bsdf = intrinsic_bsdf(truth);
        Rgb c(0.0f);
        for (int k = 0; k < K; ++k) {
            Vec3 d = unit();
            if (dot(d, n) < 0.0f) d = -d;
            const float v = shadows ? rng.next_float() : 1.0f;
            const Rgb ind = shadows ? Rgb(0.1f * rng.next_float()) : Rgb(0.0f);
            s.dir.push_back(d);
            s.visibility.push_back(v);
            s.indirect.push_back(ind);
            const Vec3 wi = frame.to_local(d);
            c += (Rgb(v) + ind) * materials::bsdf_eval(bsdf, frame.to_local(wo), wi) *
                 (wi.z * 6.2831853f / float(K));
        }
        s.target.push_back(c);
    }
    return s;
}

// Pixel squares (RelightSamples::footprint) of `side` model units across each sample's camera ray, the ray
// crossing each at a random place.
void add_pixel_squares(RelightSamples& s, float side, Pcg32 rng) {
    s.footprint.clear();
    for (size_t i = 0; i < s.size(); ++i) {
        const Frame f = Frame::from_z(s.wo[i]);
        PixelFootprint fp;
        fp.u = f.to_world(Vec3(side, 0.0f, 0.0f));
        fp.v = f.to_world(Vec3(0.0f, side, 0.0f));
        fp.corner = -(fp.u * rng.next_float() + fp.v * rng.next_float());
        s.footprint.push_back(fp);
    }
}

// Every pairing of the shading estimators (relight_trainer.h): the sums over the directions, the diffuse ratio,
// the specular split sum.
void expect_gradient_matches_finite_differences(SpecularEstimate estimate, DiffuseEstimate diffuse,
                                                float huber_delta = 0.0f,
                                                IntrinsicDiffuse lobe = IntrinsicDiffuse::burley,
                                                int pooled = 0, int footprint = 1) {
    const NerfModel m = small_model();
    RelightSamples s = synthetic_samples(64, 8, true);
    // Pixel squares a few grid cells wide, so that the footprint's queries read different entries.
    if (footprint > 1) add_pixel_squares(s, 0.03f, Pcg32(5, 6));
    // Pooled neighbours (any lit points will do for the gradient; some lists end early), whose directions
    // partly fall below a point's horizon.
    s.neighbours = pooled;
    for (uint32_t i = 0; i < 64 && pooled > 0; ++i)
        for (int k = 0; k < pooled; ++k)
            s.neighbour.push_back(i % 5 == 0 && k > 0 ? RelightSamples::k_no_neighbour : (i + 1 + uint32_t(k)) % 64);
    RelightTrainSettings ts;
    ts.intrinsic = small_intrinsic();
    ts.intrinsic.diffuse = lobe;
    ts.batch = 64;
    ts.env_width = 8;
    ts.env_height = 4;
    ts.roughness_prior = 0.05f;  // large enough to show in the MLP's gradient
    ts.specular = estimate;
    ts.diffuse = diffuse;
    ts.huber_delta = huber_delta;
    ts.footprint_queries = footprint;
    RelightTrainer tr(m, 2, s, ts);
    // Move away from the initial point so that every term has a gradient.
    for (int i = 0; i < 20; ++i) tr.step();
    std::vector<float> g;
    tr.gradient(g);
    std::vector<float>& p = tr.raw_params();
    // The largest-gradient parameters of each group; central differences in double of the float objective.
    auto check = [&](size_t begin, size_t end, const char* what) {
        size_t best = begin;
        for (size_t i = begin; i < end; ++i)
            if (std::fabs(g[i]) > std::fabs(g[best])) best = i;
        ASSERT_GT(std::fabs(g[best]), 0.0f) << what;
        const float saved = p[best], h = 1e-2f * std::max(1.0f, std::fabs(saved));
        std::vector<float> scratch;
        p[best] = saved + h;
        const double up = tr.gradient(scratch).objective;
        p[best] = saved - h;
        const double down = tr.gradient(scratch).objective;
        p[best] = saved;
        const double fd = (up - down) / (2.0 * h);
        // The roughness derivative inside the analytic gradient is itself a difference of step 0.01, and the
        // objective is float: 10% covers both at this step size (a wrong sign or factor is far outside).
        EXPECT_NEAR(g[best], fd, 0.1 * std::fabs(fd) + 1e-7) << what << " parameter " << best;
    };
    const IntrinsicLayout& l = tr.layout();
    check(l.mlp_offset, l.grid_offset, "MLP weight");
    check(l.grid_offset, l.total, "hash-grid entry");
    check(tr.environment_offset(), tr.exposure_offset(), "environment texel");
    check(tr.exposure_offset(), p.size(), "exposure");
}

TEST(RelightTrainer, GradientMatchesFiniteDifferencesOfItsObjective) {
    expect_gradient_matches_finite_differences(SpecularEstimate::sampled, DiffuseEstimate::sampled);
}

TEST(RelightTrainer, PrefilteredGradientMatchesFiniteDifferencesOfItsObjective) {
    expect_gradient_matches_finite_differences(SpecularEstimate::prefiltered, DiffuseEstimate::ratio);
}

TEST(RelightTrainer, DiffuseRatioWithSampledSpecularGradientMatchesFiniteDifferences) {
    expect_gradient_matches_finite_differences(SpecularEstimate::sampled, DiffuseEstimate::ratio);
}

// The layered diffuse (the first relightable models'), whose ratio weights do not depend on the roughness.
TEST(RelightTrainer, LayeredDiffuseGradientMatchesFiniteDifferences) {
    expect_gradient_matches_finite_differences(SpecularEstimate::prefiltered, DiffuseEstimate::ratio, 0.0f,
                                               IntrinsicDiffuse::layered);
    expect_gradient_matches_finite_differences(SpecularEstimate::sampled, DiffuseEstimate::sampled, 0.0f,
                                               IntrinsicDiffuse::layered);
}

// The fit keeps each light direction's environment lookup packed in 8 bytes: the same texels and weights as
// env_taps to the 16-bit fractions' rounding, across the seam at u = 0 and at both poles.
TEST(RelightEnv, PackedTapsMatchTheLookup) {
    Pcg32 rng(3, 4);
    std::vector<Vec3> dirs = {Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(-1, 0, 0), Vec3(-1, 1e-7f, 0), Vec3(-1, -1e-7f, 0),
                              normalize(Vec3(1e-4f, 0, 1))};
    for (int i = 0; i < 20000; ++i) {
        const float z = 1.0f - 2.0f * rng.next_float(), phi = 6.2831853f * rng.next_float();
        const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
        dirs.push_back(Vec3(r * std::cos(phi), r * std::sin(phi), z));
    }
    for (const auto& [w, h] : {std::pair{32, 16}, std::pair{8, 4}, std::pair{2, 1}, std::pair{4096, 4096}})
        for (const Vec3 d : dirs) {
            const EnvTaps a = env_taps(w, h, d), b = unpack_env_taps(w, h, pack_env_taps(w, h, d));
            // Equal texels, or a weight of (almost) zero where a fraction rounded across a texel's edge.
            Rgb sum_b(0.0f);
            for (int k = 0; k < 4; ++k) {
                ASSERT_GE(b.index[k], 0);
                ASSERT_LT(b.index[k], w * h);
                if (a.index[k] != b.index[k]) ASSERT_LT(std::max(a.weight[k], b.weight[k]), 1e-4f) << w << "x" << h;
                ASSERT_NEAR(a.weight[k], b.weight[k], 2e-5f) << w << "x" << h;
                sum_b += Rgb(b.weight[k]);
            }
            ASSERT_NEAR(sum_b.x, 1.0f, 1e-5f);
        }
}

// Each point also shaded with its pooled neighbours' directions (RelightSampleSettings::pooled_neighbours).
TEST(RelightTrainer, PooledDirectionsGradientMatchesFiniteDifferences) {
    expect_gradient_matches_finite_differences(SpecularEstimate::prefiltered, DiffuseEstimate::ratio, 0.0f,
                                               IntrinsicDiffuse::burley, 3);
    expect_gradient_matches_finite_differences(SpecularEstimate::sampled, DiffuseEstimate::sampled, 0.0f,
                                               IntrinsicDiffuse::burley, 2);
}

// The fields averaged over each pixel's square (RelightTrainSettings::footprint_queries), 2x2 and 3x3.
TEST(RelightTrainer, FootprintAverageGradientMatchesFiniteDifferences) {
    expect_gradient_matches_finite_differences(SpecularEstimate::prefiltered, DiffuseEstimate::ratio, 0.0f,
                                               IntrinsicDiffuse::burley, 2, 4);
    expect_gradient_matches_finite_differences(SpecularEstimate::sampled, DiffuseEstimate::sampled, 0.0f,
                                               IntrinsicDiffuse::burley, 0, 9);
}

TEST(RelightTrainer, AnAverageDecayOutsideZeroToOneIsAnError) {
    const NerfModel m = small_model();
    const RelightSamples s = synthetic_samples(16, 4, false);
    RelightTrainSettings ts;
    ts.intrinsic = small_intrinsic();
    for (float bad : {1.0f, -0.1f, std::nanf("")}) {
        ts.average_decay = bad;
        EXPECT_THROW(RelightTrainer(m, 2, s, ts), Error) << bad;
    }
}

TEST(RelightTrainer, FootprintQueriesAreCheckedAgainstTheSamples) {
    const NerfModel m = small_model();
    const RelightSamples s = synthetic_samples(16, 4, false);  // no pixel squares
    RelightTrainSettings ts;
    ts.intrinsic = small_intrinsic();
    ts.footprint_queries = 4;
    EXPECT_THROW(RelightTrainer(m, 2, s, ts), Error);
    ts.footprint_queries = 3;
    EXPECT_THROW(RelightTrainer(m, 2, s, ts), Error);
}

// The square of a pixel at a point its ray meets: the rays through the pixel's corners meet the square's
// corners at the point's depth, in a model space that scales and moves the world (NeRF-synthetic's).
TEST(PixelFootprint, SpansThePixelAtThePointsDepth) {
    Camera cam;
    cam.width = 64;
    cam.height = 48;
    cam.fx = 70.0f;
    cam.fy = 60.0f;
    cam.cx = 31.0f;
    cam.cy = 25.0f;
    // A turned and moved camera (a unit quaternion of no special angle).
    const double q[4] = {0.3, -0.5, 0.2, 0.7}, qn = std::sqrt(0.09 + 0.25 + 0.04 + 0.49);
    cam.camera_to_world =
        Mat4::translation(2.0, -3.0, 1.5) * Mat4::rotation_quat(q[0] / qn, q[1] / qn, q[2] / qn, q[3] / qn);
    const Mat4 w2m = ngp_world_to_model(0.33f, Vec3(0.5f));
    const float px = 20.3f, py = 33.8f, t = 2.7f;  // t: world distance along the ray
    const Ray r = generate_pixel_ray(cam, px, py);
    const Vec3 p = w2m.transform_point(r.o + r.d * t);
    const PixelFootprint f = pixel_footprint(cam, w2m, p, px, py);
    const Vec3 eye = w2m.transform_point(r.o);
    // The camera's depth of p, then the model-space point at that depth on the ray through pixel (x, y).
    const Vec3 fwd = w2m.transform_vector(cam.camera_to_world.transform_vector(Vec3(0.0f, 0.0f, -1.0f)));
    const float depth = dot(p - eye, fwd);
    const auto at_depth = [&](float x, float y) {
        const Ray q = generate_pixel_ray(cam, x, y);
        const Vec3 d = w2m.transform_vector(q.d);
        return eye + d * (depth / dot(d, fwd));
    };
    const Vec3 corner = p + f.corner;
    const auto near = [](Vec3 a, Vec3 b) { return length(a - b) < 1e-4f * std::max(1.0f, length(b)); };
    EXPECT_TRUE(near(corner, at_depth(20.0f, 33.0f)));
    EXPECT_TRUE(near(corner + f.u, at_depth(21.0f, 33.0f)));
    EXPECT_TRUE(near(corner + f.v, at_depth(20.0f, 34.0f)));
    EXPECT_TRUE(near(corner + f.u + f.v, at_depth(21.0f, 34.0f)));
    EXPECT_TRUE(near(corner + f.u * 0.3f + f.v * 0.8f, p));
}

// The capture light starts darker below the training world's horizon (RelightTrainSettings::ground_share): the
// world's +z, which the NeRF-synthetic model space turns into another axis (ngp_world_to_model), not model +z.
TEST(RelightTrainer, TheEnvironmentStartsDarkerBelowTheWorldsHorizon) {
    const NerfModel m = small_model();
    const RelightSamples s = synthetic_samples(16, 4, false);
    RelightTrainSettings ts;
    ts.intrinsic = small_intrinsic();
    ts.batch = 16;
    ts.env_width = 8;
    ts.env_height = 8;
    ts.ground_share = 0.25f;
    RelightTrainer tr(m, 2, s, ts);
    const std::vector<float>& p = tr.raw_params();
    const Mat4 model_to_world = m.world_to_model.inverse();
    const auto world_z = [&](int i, int j) {
        return model_to_world.transform_vector(env_texel_direction(ts.env_width, ts.env_height, i, j)).z;
    };
    float sky = std::numeric_limits<float>::quiet_NaN();
    for (int t = 0; t < ts.env_width * ts.env_height && std::isnan(sky); ++t)
        if (world_z(t % ts.env_width, t / ts.env_width) >= 0.0f) sky = p[tr.environment_offset() + size_t(t) * 3];
    int below = 0, above = 0;
    for (int j = 0; j < ts.env_height; ++j)
        for (int i = 0; i < ts.env_width; ++i) {
            const bool is_sky = world_z(i, j) >= 0.0f;
            const float* texel = &p[tr.environment_offset() + size_t(j * ts.env_width + i) * 3];
            for (int c = 0; c < 3; ++c) {
                if (is_sky) {
                    EXPECT_FLOAT_EQ(texel[c], sky) << i << " " << j;
                } else {
                    EXPECT_NEAR(texel[c], sky + std::log(0.25f), 1e-5f) << i << " " << j;
                }
            }
            (is_sky ? above : below)++;
        }
    EXPECT_GT(below, 16);
    EXPECT_GT(above, 16);
}

// A threshold well inside the residuals this fit has after 20 steps, so that both branches are taken.
TEST(RelightTrainer, HuberLossGradientMatchesFiniteDifferences) {
    expect_gradient_matches_finite_differences(SpecularEstimate::sampled, DiffuseEstimate::sampled, 0.02f);
}

TEST(RelightTrainer, PrefilteredSpecularWithSampledDiffuseGradientMatchesFiniteDifferences) {
    expect_gradient_matches_finite_differences(SpecularEstimate::prefiltered, DiffuseEstimate::sampled);
}

// The recovery tests' fit: a grid fine enough for true_albedo's pattern, an 8x4 sky, exposures fixed.
RelightTrainSettings recovery_settings(SpecularEstimate estimate) {
    RelightTrainSettings ts;
    ts.intrinsic = small_intrinsic();
    ts.intrinsic.grid = {6, 2, 14, 8, 1.5f};  // enough entries for the pattern's finest level without collisions
    ts.intrinsic.finest_resolution = 128.0f;
    ts.intrinsic.width = 32;
    ts.batch = 256;
    ts.env_width = 8;
    ts.env_height = 4;
    ts.learn_exposure = false;
    // These fits' sky is uniform, as bright below the horizon as above: the start that matches it. The default
    // start (a ground at 0.1 of the sky, which dev's capture light and most real ones have) left the Burley fit
    // 3-4x the albedo error here (0.16-0.22 against 0.05-0.09): a bright ground is what it gets wrong.
    ts.ground_share = 1.0f;
    ts.specular = estimate;
    // As `nerfpt train --relight-specular prefiltered` pairs it: with the diffuse ratio.
    ts.diffuse = estimate == SpecularEstimate::prefiltered ? DiffuseEstimate::ratio : DiffuseEstimate::sampled;
    return ts;
}

// Relative RMS error of the fitted albedo at every 4th point after the per-channel scale no image can fix.
double relative_albedo_error(const IntrinsicFieldView& view, const RelightSamples& s) {
    double num[3] = {0, 0, 0}, den[3] = {0, 0, 0};
    std::vector<Rgb> got, want;
    for (size_t i = 0; i < s.size(); i += 4) {
        got.push_back(view.query(s.position[i]).albedo);
        want.push_back(true_albedo(s.position[i]));
        for (int c = 0; c < 3; ++c) {
            num[c] += double(got.back()[c]) * want.back()[c];
            den[c] += double(got.back()[c]) * got.back()[c];
        }
    }
    double err = 0, norm = 0;
    for (size_t i = 0; i < got.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            const double d = got[i][c] * num[c] / den[c] - want[i][c];
            err += d * d;
            norm += double(want[i][c]) * want[i][c];
        }
    return std::sqrt(err / norm);
}

TEST(RelightTrainer, RecoversAKnownAlbedoUpToOneScalePerChannel) {
    const NerfModel m = small_model();
    const RelightSamples s = synthetic_samples(2048, 16, true);
    // The estimator the targets were made with.
    RelightTrainer tr(m, 2, s, recovery_settings(SpecularEstimate::sampled));
    RelightStepStats st;
    for (int i = 0; i < 1500; ++i) st = tr.step();  // the stage's default; ~43 dB by then (35 at 1000)
    // The fit reproduces the targets: sRGB PSNR of the last batch.
    EXPECT_GT(-10.0 * std::log10(st.mse), 35.0);
    NerfModel fitted = m;
    fitted.relight = tr.fields(1.0);
    const IntrinsicFieldView view = fitted.intrinsic();
    double normal_err = 0;
    size_t n = 0;
    for (size_t i = 0; i < s.size(); i += 4, ++n)
        normal_err += std::acos(std::min(1.0f, dot(view.query(s.position[i]).normal, s.normal[i])));
    // The targets are exact for this estimator, so what remains is the fit's own error.
    EXPECT_LT(relative_albedo_error(view, s), 0.05);
    EXPECT_LT(normal_err / double(n) * 57.29578, 5.0);  // degrees
}

// Pixels that average the albedo over their squares (as a photo's do), fitted with the fields read at one
// place per pixel and averaged over 2x2 places: the second recovers the albedo itself, the first its blur.
// Squares of 0.04 units across the rays to the sphere of synthetic_samples (the texture's period is
// 0.16-0.2), targets made with the square's mean albedo from a 6x6 grid on the tangent plane, where the
// pixel's own rays meet it (moved as the fit moves its places: not where the ray grazes the plane). The
// blurred targets' albedo is 17% (RMS) from the sharp one.
TEST(RelightTrainer, TheFootprintAverageUndoesThePixelsBlur) {
    const NerfModel m = small_model();
    RelightSamples s = synthetic_samples(2048, 16, true);
    add_pixel_squares(s, 0.04f, Pcg32(9, 10));
    for (size_t i = 0; i < s.size(); ++i) {
        const PixelFootprint& fp = s.footprint[i];
        const Vec3 d = -s.wo[i], n = s.normal[i];
        Rgb mean(0.0f);
        for (int y = 0; y < 6; ++y)
            for (int x = 0; x < 6; ++x) {
                const Vec3 off = fp.corner + fp.u * ((x + 0.5f) / 6.0f) + fp.v * ((y + 0.5f) / 6.0f);
                const float dn = dot(d, n);
                mean += true_albedo(s.position[i] + off +
                                    (std::fabs(dn) > 0.2f ? d * (-dot(off, n) / dn) : Vec3(0.0f)));
            }
        mean = mean * (1.0f / 36.0f);
        // The target is linear in the albedo (diffuse) plus the specular part: scale its albedo-dependent
        // part.
        const Rgb a = true_albedo(s.position[i]);
        IntrinsicSample black;
        black.albedo = Rgb(0.0f);
        black.roughness = 0.5f;
        black.diffuse = IntrinsicConfig{}.diffuse;
        const Frame nf = Frame::from_z(n);
        Rgb spec(0.0f);
        for (int k = 0; k < s.directions; ++k) {
            const size_t sk = i * size_t(s.directions) + size_t(k);
            const Vec3 wi = nf.to_local(s.dir[sk]);
            spec += (Rgb(s.visibility[sk]) + s.indirect[sk]) *
                    materials::bsdf_eval(intrinsic_bsdf(black), nf.to_local(s.wo[i]), wi) *
                    (wi.z * 6.2831853f / float(s.directions));
        }
        for (int c = 0; c < 3; ++c) s.target[i][c] = spec[c] + (s.target[i][c] - spec[c]) * mean[c] / a[c];
    }
    double err[2];
    for (int j = 0; j < 2; ++j) {
        RelightTrainSettings ts = recovery_settings(SpecularEstimate::sampled);
        ts.footprint_queries = j == 0 ? 1 : 4;
        RelightTrainer tr(m, 2, s, ts);
        for (int i = 0; i < 1500; ++i) tr.step();
        NerfModel fitted = m;
        fitted.relight = tr.fields(1.0);
        err[j] = relative_albedo_error(fitted.intrinsic(), s);
    }
    // Measured with the stage's default average (0.99): 0.174 at one place (the blur), 0.073 averaged (0.175 and
    // 0.071 with 0.95); the unblurred fit of RecoversAKnownAlbedo...: 0.036.
    EXPECT_LT(err[1], 0.09) << "one place: " << err[0];
    EXPECT_GT(err[0], 2.0 * err[1]);
}

// The fields the stage delivers are the parameters' moving average with the settings' decay per step: with 0
// they are the last step's parameters, with more the average of more steps, which moves less the longer it
// is.
TEST(RelightTrainer, TheFieldsAreTheParametersAverage) {
    const NerfModel m = small_model();
    const RelightSamples s = synthetic_samples(512, 8, true);
    const float decays[3] = {0.0f, 0.95f, 0.99f};
    double dist[3] = {0, 0, 0};  // of the fields from the last step's parameters
    for (int j = 0; j < 3; ++j) {
        RelightTrainSettings ts = recovery_settings(SpecularEstimate::sampled);
        ts.average_decay = decays[j];
        RelightTrainer tr(m, 2, s, ts);
        for (int i = 0; i < 200; ++i) tr.step();
        const std::vector<float> fields = tr.fields(1.0).params;
        ASSERT_EQ(fields.size(), size_t(tr.layout().total));
        for (size_t i = 0; i < fields.size(); ++i)
            dist[j] += std::fabs(double(fields[i]) - tr.raw_params()[i]);
    }
    EXPECT_EQ(dist[0], 0.0);
    EXPECT_GT(dist[1], 0.0);
    EXPECT_GT(dist[2], dist[1]);
}

// The directional albedos of intrinsic_bsdf under a uniform white sky with nothing in the way, by a midpoint
// rule fine enough for a roughness-0.3 lobe (~4 degrees about the mirror direction; cells of 0.7 x 0.7
// degrees): the diffuse factor D (per unit base colour) and the specular E, at n_mu view cosines.
struct ExactShading {
    static constexpr int n_mu = 24;
    float diffuse[n_mu], specular[n_mu];
    ExactShading(float roughness, IntrinsicDiffuse lobe) {
        IntrinsicSample one, zero;
        one.roughness = zero.roughness = roughness;
        one.albedo = Rgb(1.0f);
        zero.albedo = Rgb(0.0f);
        one.diffuse = zero.diffuse = lobe;
        const materials::Bsdf b1 = intrinsic_bsdf(one), b0 = intrinsic_bsdf(zero);
        constexpr int n_theta = 128, n_phi = 512;
        for (int m = 0; m < n_mu; ++m) {
            const float mu = mu_at(m);
            const Vec3 wo(std::sqrt(1.0f - mu * mu), 0.0f, mu);
            double d = 0, e = 0;
            for (int i = 0; i < n_theta; ++i) {
                const double th = (i + 0.5) * 0.5 * M_PI / n_theta;
                const double dw = std::sin(th) * (0.5 * M_PI / n_theta) * (2 * M_PI / n_phi);
                for (int j = 0; j < n_phi; ++j) {
                    const double ph = (j + 0.5) * 2 * M_PI / n_phi;
                    const Vec3 wi(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)),
                                  float(std::cos(th)));
                    const float f1 = materials::bsdf_eval(b1, wo, wi).x, f0 = materials::bsdf_eval(b0, wo, wi).x;
                    d += (f1 - f0) * wi.z * dw;
                    e += f0 * wi.z * dw;
                }
            }
            diffuse[m] = float(d);
            specular[m] = float(e);
        }
    }
    static float mu_at(int m) { return 0.05f + 0.95f * float(m) / float(n_mu - 1); }
    // Linear in mu between the tabulated cosines.
    void at(float mu, float* d, float* e) const {
        const float x = std::clamp((mu - 0.05f) / 0.95f, 0.0f, 1.0f) * float(n_mu - 1);
        const int i = std::min(int(x), n_mu - 2);
        const float a = x - float(i);
        *d = (1 - a) * diffuse[i] + a * diffuse[i + 1];
        *e = (1 - a) * specular[i] + a * specular[i + 1];
    }
};

// Points on the sphere of synthetic_samples under a uniform white sky, no shadows, a glossy dielectric
// (roughness 0.3): targets are the exact shading a * D(mu_o) + E(mu_o) (ExactShading), not any estimator of it.
// Returns the relative RMS albedo error after the per-channel scale, and the mean fitted roughness.
struct GlossyFit {
    double albedo_error = 0, roughness = 0;
};
GlossyFit fit_glossy_sphere(SpecularEstimate estimate, float roughness, IntrinsicDiffuse lobe) {
    const ExactShading exact(roughness, lobe);
    RelightSamples s = synthetic_samples(2048, 8, false);
    for (size_t i = 0; i < s.size(); ++i) {
        float d, e;
        exact.at(dot(s.wo[i], s.normal[i]), &d, &e);
        s.target[i] = true_albedo(s.position[i]) * d + Rgb(e);
    }
    RelightTrainSettings ts = recovery_settings(estimate);
    ts.intrinsic.diffuse = lobe;  // the targets' lobe
    RelightTrainer tr(small_model(), 2, s, ts);
    for (int i = 0; i < 1500; ++i) tr.step();
    NerfModel fitted = small_model();
    fitted.relight = tr.fields(1.0);
    const IntrinsicFieldView view = fitted.intrinsic();
    GlossyFit fit;
    fit.albedo_error = relative_albedo_error(view, s);
    size_t n = 0;
    for (size_t i = 0; i < s.size(); i += 4, ++n) fit.roughness += view.query(s.position[i]).roughness;
    fit.roughness /= double(n);
    return fit;
}

// With 8 light directions per point a glossy lobe is missed almost always (at roughness 0.3 and at 0.6, inside
// the dev set's 0.3-0.8): the sampled estimator puts the sky's
// reflection into the albedo (an offset that no per-channel scale removes); the prefiltered one does not. (Under
// a uniform sky the roughness barely changes the shading, so it is printed, not checked.)
TEST(RelightTrainer, PrefilteredSpecularRecoversAGlossyAlbedo) {
    for (const IntrinsicDiffuse lobe : {IntrinsicDiffuse::layered, IntrinsicDiffuse::burley})
        for (const float roughness : {0.3f, 0.6f}) {
            const GlossyFit pre = fit_glossy_sphere(SpecularEstimate::prefiltered, roughness, lobe);
            const GlossyFit sampled = fit_glossy_sphere(SpecularEstimate::sampled, roughness, lobe);
            const bool burley = lobe == IntrinsicDiffuse::burley;
            std::printf("%s, roughness %.1f: relative albedo error: prefiltered %.4f, sampled %.4f; mean roughness "
                        "%.3f / %.3f\n",
                        burley ? "Burley" : "layered", roughness, pre.albedo_error, sampled.albedo_error,
                        pre.roughness, sampled.roughness);
            // What the estimator is for: well under half the sampled estimate's error, with either lobe.
            EXPECT_LT(pre.albedo_error, 0.5 * sampled.albedo_error) << "roughness " << roughness;
            // Regression bounds, not derived: the layered lobe's 0.08 predates Burley's (0.053 and 0.061 measured,
            // the fit's own 0.05 on exact targets with room for the tables). Burley's was set after measuring
            // 0.048 and 0.093 (against 0.24 and 0.23 sampled): under a uniform sky its roughness-dependent
            // grazing brightness trades against the albedo point by point, so its bound is looser.
            EXPECT_LT(pre.albedo_error, burley ? 0.12 : 0.08) << "roughness " << roughness;
        }
}

}  // namespace
}  // namespace npt::nerf

namespace npt::nerf {
namespace {

// The wavefront marcher (rounds of samples, batched evaluation) against one ray at a time through the per-point
// query: the same samples, the same sums, so agreement to float rounding; events where the sequential optical
// depth first reaches the target.
TEST(WavefrontMarch, MatchesTheSequentialMarchOfEachRay) {
    NerfConfig cfg;
    cfg.encoding.grid.levels = 4;
    cfg.encoding.grid.log2_table_size = 12;
    cfg.occupancy.resolution = 16;
    NerfModel m = create_model(cfg, 1.0f, ngp_world_to_model(0.33f, Vec3(0.5f)));
    Pcg32 rng(5, 6);
    // Dense enough that some rays turn opaque (optical depth ~10 over a ray): positive features through
    // positive density weights.
    const NerfLayout layout = m.layout();
    for (size_t i = layout.density_offset; i < layout.color_offset; ++i) m.params[i] = std::fabs(m.params[i]);
    for (size_t i = layout.grid_offset; i < m.params.size(); ++i) m.params[i] = rng.next_float() * 0.55f;
    const NerfFieldView field = m.field();
    const MarchParams mp = m.march_params();
    std::vector<WaveRay> rays(300);
    for (auto& r : rays) {
        const Vec3 o(rng.next_float() * 2.0f - 0.5f, -0.6f, rng.next_float());
        const Vec3 target(rng.next_float(), rng.next_float(), rng.next_float());
        r.ray = Ray{o, normalize(target - o)};
        r.jitter = rng.next_float();
        r.tau_target = 0.5f + 3.0f * rng.next_float();
    }
    std::vector<WaveRay> events = rays;
    auto query = make_cpu_field_query(m);
    march_wavefront(m, *query, rays, WaveMode::radiance);
    march_wavefront(m, *query, events, WaveMode::event);
    int opaque = 0, with_event = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
        double log_t = 0, tau = 0;
        Rgb rad(0.0f);
        bool event = false;
        Vec3 ev(0.0f);
        march_ray_visit(mp, m.occupancy.view(), rays[i].ray, rays[i].jitter, [&](const MarchSample& s) {
            float sigma;
            Rgb c;
            field.query(s.position, rays[i].ray.d, &sigma, &c);
            const double d = double(sigma) * s.dt;
            if (!event) {
                tau += d;
                if (tau >= events[i].tau_target) {
                    event = true;
                    ev = s.position;
                }
            }
            if (log_t > -9.2103404) {
                const Rgb lin(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z));
                rad += lin * float(std::exp(log_t) * -std::expm1(-d));
                log_t -= d;
            }
            return true;
        });
        const float t = log_t < -9.2103404 ? 0.0f : float(std::exp(log_t));
        opaque += t == 0.0f;
        EXPECT_NEAR(rays[i].transmittance, t, 1e-4f + 1e-3f * t) << i;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(rays[i].radiance[c], rad[c], 1e-4f + 1e-3f * rad[c]) << i;
        ASSERT_EQ(events[i].has_event, event) << i;
        if (event) {
            ++with_event;
            EXPECT_NEAR(length(events[i].event_position - ev), 0.0f, 1e-5f) << i;
        }
    }
    // Both kinds of ray are exercised.
    EXPECT_GT(opaque, 10);
    EXPECT_LT(opaque, 290);
    EXPECT_GT(with_event, 10);
}

}  // namespace
}  // namespace npt::nerf
