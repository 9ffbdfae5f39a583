// The film's outputs beside the colour on the CPU backend (render/film.h): --transparent's alpha and premultiplied
// RGB, and the albedo, normal and depth AOVs, against closed forms. The colour of a transparent render uses the same
// random numbers as the opaque one at the same seed, and only the background seen directly differs, so most checks
// are exact: opaque = transparent RGB + (1 - alpha) x sky per pixel up to float rounding (the compositing identity,
// which holds sample by sample under a constant sky). Constant volumes are marched exactly, so their alpha is the
// analytic 1 - transmittance to float rounding. AOVs of a flat quad are constant where it covers a pixel; the depth
// is an average of samples inside the pixel, hence between the least and the largest distance over the pixel.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/image_io.h"
#include "film_test_scenes.h"
#include "render/film.h"
#include "render/renderer.h"
#include "scene/scene.h"
#include "test_support.h"

namespace npt::render {
namespace {

namespace fs = std::filesystem;

float radius(Vec2 p) { return std::sqrt(p.x * p.x + p.y * p.y); }

Image render_cpu_film(const scene::Scene& s, int w, int h, int spp, bool transparent, uint32_t aov_mask,
                      AovImages* aovs, uint64_t seed = 1) {
    RenderOptions o;
    o.width = w;
    o.height = h;
    o.spp = spp;
    o.seed = seed;
    o.threads = 1;
    o.transparent = transparent;
    o.aovs = aov_mask;
    return render(s, resolve_options(s, o), {}, aovs);
}

TEST(Film, AovListsParseAndBadNamesAreNamed) {
    EXPECT_EQ(parse_aov_list("albedo"), uint32_t(k_aov_albedo));
    EXPECT_EQ(parse_aov_list("depth,albedo"), uint32_t(k_aov_albedo | k_aov_depth));
    EXPECT_EQ(parse_aov_list("albedo,normal,depth"), uint32_t(k_aov_albedo | k_aov_normal | k_aov_depth));
    test::expect_error_message([] { parse_aov_list("albedo,normals"); }, {"'normals'", "albedo, normal, depth"});
    test::expect_error_message([] { parse_aov_list(""); }, {"empty"});
    test::expect_error_message([] { parse_aov_list("albedo,"); }, {"'albedo,'", "empty"});
    test::expect_error_message([] { parse_aov_list("Albedo"); }, {"'Albedo'"});
}

// A diffuse sphere under a bright sky: alpha 1 on it, 0 off it, no colour off it, and the sphere's colour the
// opaque render's (sample for sample: only what the camera rays see of the sky is left out).
TEST(Film, TransparentLeavesOutOnlyTheSkySeenDirectly) {
    const Rgb sky(0.5f, 0.6f, 0.7f);
    const scene::Scene s = test::sphere_under_sky(Rgb(0.8f, 0.3f, 0.2f), sky);
    const int w = 40, h = 32, spp = 16;
    const Image opaque = render_cpu_film(s, w, h, spp, false, 0, nullptr);
    const Image film = render_cpu_film(s, w, h, spp, true, 0, nullptr);
    ASSERT_EQ(opaque.channels, 3);
    ASSERT_EQ(film.channels, 4);

    // The silhouette on the image plane (the sphere is on the axis): a circle of radius r / sqrt(D^2 - r^2).
    const float r_in = test::LatLongSphere::inscribed_radius(s.meshes[0]), d = 4.0f;
    const float rho_in = r_in / std::sqrt(d * d - r_in * r_in), rho_out = 1.0f / std::sqrt(d * d - 1.0f);
    int inside = 0, outside = 0, edge = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float far_corner = 0.0f;
            for (int c = 0; c < 4; ++c)
                far_corner = std::max(far_corner, radius(test::image_plane_point(s.cameras[0], w, h, float(x + (c & 1)),
                                                                                  float(y + (c >> 1)))));
            // The pixel's nearest point to the axis.
            const Vec2 a = test::image_plane_point(s.cameras[0], w, h, float(x), float(y));
            const Vec2 b = test::image_plane_point(s.cameras[0], w, h, float(x + 1), float(y + 1));
            const float nx = std::clamp(0.0f, std::min(a.x, b.x), std::max(a.x, b.x));
            const float ny = std::clamp(0.0f, std::min(a.y, b.y), std::max(a.y, b.y));
            const float near_point = std::sqrt(nx * nx + ny * ny);
            const float* f = film.at(x, y);
            const Rgb o = opaque.rgb(x, y);
            if (far_corner < rho_in) {
                ++inside;
                EXPECT_EQ(f[3], 1.0f) << x << "," << y;
                for (int c = 0; c < 3; ++c) EXPECT_EQ(f[c], o[c]) << x << "," << y;
            } else if (near_point > rho_out) {
                ++outside;
                EXPECT_EQ(f[3], 0.0f) << x << "," << y;
                for (int c = 0; c < 3; ++c) EXPECT_EQ(f[c], 0.0f) << x << "," << y;
            } else if (f[3] > 0.0f && f[3] < 1.0f) {
                ++edge;
            }
            // Compositing over the sky gives the opaque render back, on the edge too.
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(f[c] + (1.0f - f[3]) * sky[c], o[c], 2e-6f * (1.0f + o[c])) << x << "," << y;
        }
    EXPECT_GT(inside, 100);
    EXPECT_GT(outside, 100);
    EXPECT_GT(edge, 10);
}

// A constant cube volume (sigma 6 per unit, side 0.5) seen through its faces: alpha = 1 - exp(-sigma x chord), the
// colour its emission only (no sky behind it); in front of a quad, the quad is the first event, weighed by the
// volume's transmittance.
TEST(Film, VolumeAlphaIsOneMinusItsTransmittance) {
    const fs::path dir = test::temp_dir();
    const Vec3 srgb(0.8f, 0.5f, 0.2f);
    const Vec3 linear(srgb_to_linear(srgb.x), srgb_to_linear(srgb.y), srgb_to_linear(srgb.z));
    const float sigma = 6.0f;
    scene::Scene s;
    s.source = dir / "scene.gltf";
    s.environment.color = Vec3(0.1f, 0.2f, 0.3f);
    s.volumes = {test::constant_cube_volume(dir, Vec3(0.0f), 0.25f, srgb)};

    // One camera ray through the centre, through the integrator directly.
    {
        SceneData data(s, 8, 8);
        cpu::EmbreeScene embree(s);
        cpu::EmbreeTracer tracer(embree);
        PathSettings ps;
        ps.transparent_background = true;
        Pcg32 rng(1, 2);
        FirstHit first;
        first.weight = 7.0f;  // trace_path starts the record afresh
        const Rgb l = trace_path(data.view(), tracer, Ray{{0, 0, 3}, {0, 0, -1}}, rng, ps, &first);
        const float t = std::exp(-sigma * 0.5f);
        EXPECT_NEAR(first.escaped, t, 1e-3f * t);
        EXPECT_EQ(first.weight, 0.0f);  // an emission-absorption volume is no scattering event
        test::expect_near(first.albedo, Rgb(0.0f), 0.0f);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(l[c], linear[c] * (1.0f - t), 1e-3f * linear[c]);
    }

    // A whole render through a narrow camera: every pixel's rays cross the front and back faces, with chords
    // between 0.5 (the axis) and 0.5 / cos(the widest ray's angle).
    s.cameras = {test::film_camera(3.0f, 2.0f * float(M_PI) / 180.0f)};
    s.camera = 0;
    const Image film = render_cpu_film(s, 8, 8, 4, true, 0, nullptr);
    const float corner = radius(test::image_plane_point(s.cameras[0], 8, 8, 0.0f, 0.0f));
    const float alpha_lo = 1.0f - std::exp(-sigma * 0.5f), alpha_hi = 1.0f - std::exp(-sigma * 0.5f * std::sqrt(1.0f + corner * corner));
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            EXPECT_GE(film.at(x, y)[3], alpha_lo - 1e-4f) << x << "," << y;
            EXPECT_LE(film.at(x, y)[3], alpha_hi + 1e-4f) << x << "," << y;
        }

    // A quad behind the volume is the first event; its weight is the volume's transmittance in front of it.
    s.materials = {test::film_lambert(Rgb(0.2f, 0.4f, 0.6f))};
    s.meshes = {test::make_quad(Vec3(-1.0f, -1.0f, -1.0f), Vec3(2.0f, 0.0f, 0.0f), Vec3(0.0f, 2.0f, 0.0f), 0)};
    SceneData data(s, 8, 8);
    cpu::EmbreeScene embree(s);
    cpu::EmbreeTracer tracer(embree);
    Pcg32 rng(1, 2);
    FirstHit first;
    trace_path(data.view(), tracer, Ray{{0, 0, 3}, {0, 0, -1}}, rng, PathSettings{}, &first);
    EXPECT_EQ(first.escaped, 0.0f);
    EXPECT_NEAR(first.weight, std::exp(-sigma * 0.5f), 1e-3f * std::exp(-sigma * 0.5f));
    test::expect_near(first.albedo, Vec3(0.2f, 0.4f, 0.6f), 1e-7f);
    test::expect_near(first.normal, Vec3(0.0f, 0.0f, 1.0f), 1e-7f);
    EXPECT_NEAR(first.distance, 4.0f, 1e-5f);
}

// A quad facing the camera: its base colour, its normal and the distance where it covers a pixel, the same albedo
// and normal where it covers part of one (coverage-normalised, not darkened), nothing where it is not.
TEST(Film, AovsOfAQuadAreItsAlbedoNormalAndDistance) {
    const Rgb albedo(0.2f, 0.5f, 0.9f);
    const float x_right = 0.37f;
    const scene::Scene s = test::quad_facing_camera(albedo, x_right, Rgb(1.0f));
    const int w = 36, h = 24, spp = 8;
    AovImages aovs;
    const Image film = render_cpu_film(s, w, h, spp, true, k_aov_albedo | k_aov_normal | k_aov_depth, &aovs);
    ASSERT_EQ(aovs.albedo.channels, 3);
    ASSERT_EQ(aovs.normal.channels, 3);
    ASSERT_EQ(aovs.depth.channels, 1);
    ASSERT_EQ(aovs.depth.width, w);
    const scene::Camera& cam = s.cameras[0];
    const float d = 3.0f;  // the quad's plane is at distance 3 along the axis: t = 3 sqrt(1 + x^2 + y^2)
    auto hits = [&](Vec2 p) { return p.x * d >= -1.0f && p.x * d <= x_right && p.y * d >= -1.0f && p.y * d <= 1.0f; };
    // Which of the quad's four edge lines the point lies beyond (bit mask): corners all beyond one line miss it.
    auto beyond = [&](Vec2 p) {
        return (p.x * d < -1.0f ? 1 : 0) | (p.x * d > x_right ? 2 : 0) | (p.y * d < -1.0f ? 4 : 0) |
               (p.y * d > 1.0f ? 8 : 0);
    };
    auto t_at = [&](Vec2 p) { return d * std::sqrt(1.0f + p.x * p.x + p.y * p.y); };
    int full = 0, none = 0, partial = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            int corners_in = 0, all_beyond = 15;
            float t_max = 0.0f;
            for (int c = 0; c < 4; ++c) {
                const Vec2 p = test::image_plane_point(cam, w, h, float(x + (c & 1)), float(y + (c >> 1)));
                corners_in += hits(p);
                all_beyond &= beyond(p);
                t_max = std::max(t_max, t_at(p));
            }
            const size_t i = size_t(y) * size_t(w) + size_t(x);
            const Rgb a(aovs.albedo.pixels[3 * i], aovs.albedo.pixels[3 * i + 1], aovs.albedo.pixels[3 * i + 2]);
            const Vec3 n(aovs.normal.pixels[3 * i], aovs.normal.pixels[3 * i + 1], aovs.normal.pixels[3 * i + 2]);
            const float depth = aovs.depth.pixels[i];
            const float alpha = film.at(x, y)[3];
            if (corners_in == 4) {  // the quad is convex: the whole pixel
                ++full;
                EXPECT_EQ(alpha, 1.0f);
                test::expect_near(a, albedo, 1e-6f);
                test::expect_near(n, Vec3(0.0f, 0.0f, 1.0f), 1e-6f);
                // The samples' average lies between t's least value over the pixel (at its point nearest the
                // axis: t grows with the distance from it) and its largest (a corner).
                const Vec2 p0 = test::image_plane_point(cam, w, h, float(x), float(y));
                const Vec2 p1 = test::image_plane_point(cam, w, h, float(x + 1), float(y + 1));
                const Vec2 nearest(std::clamp(0.0f, std::min(p0.x, p1.x), std::max(p0.x, p1.x)),
                                   std::clamp(0.0f, std::min(p0.y, p1.y), std::max(p0.y, p1.y)));
                EXPECT_GE(depth, t_at(nearest) * (1.0f - 1e-6f)) << x << "," << y;
                EXPECT_LE(depth, t_max * (1.0f + 1e-6f)) << x << "," << y;
            } else if (all_beyond != 0) {  // the whole pixel beyond one edge line: it misses the quad
                ++none;
                EXPECT_EQ(alpha, 0.0f);
                test::expect_near(a, Rgb(0.0f), 0.0f);
                test::expect_near(n, Vec3(0.0f), 0.0f);
                EXPECT_EQ(depth, std::numeric_limits<float>::infinity());
            } else if (alpha > 0.0f && alpha < 1.0f) {
                ++partial;
                test::expect_near(a, albedo, 1e-6f);
                test::expect_near(n, Vec3(0.0f, 0.0f, 1.0f), 1e-6f);
            }
        }
    EXPECT_GT(full, 50);
    EXPECT_GT(none, 50);
    EXPECT_GT(partial, 5);

    // Without --transparent the AOVs are the same (the sky does not enter them) and the image stays RGB.
    AovImages opaque_aovs;
    const Image opaque = render_cpu_film(s, w, h, spp, false, k_aov_albedo | k_aov_normal | k_aov_depth, &opaque_aovs);
    EXPECT_EQ(opaque.channels, 3);
    EXPECT_EQ(opaque_aovs.albedo.pixels, aovs.albedo.pixels);
    EXPECT_EQ(opaque_aovs.normal.pixels, aovs.normal.pixels);
    EXPECT_EQ(opaque_aovs.depth.pixels, aovs.depth.pixels);
    // Only the layers asked for are made.
    AovImages some;
    render_cpu_film(s, w, h, 1, false, k_aov_depth, &some);
    EXPECT_TRUE(some.albedo.pixels.empty());
    EXPECT_TRUE(some.normal.pixels.empty());
    EXPECT_EQ(some.depth.pixels.size(), size_t(w) * size_t(h));
}

// A scene's own setting: "transparent" in the JSON scene's render block (glTF scene extras alike), and its errors.
TEST(Film, ScenesCarryTheTransparentSetting) {
    const fs::path dir = test::temp_dir();
    test::write_file(dir / "t.json", R"({"background": [1, 1, 1], "render": {"transparent": true}})");
    EXPECT_TRUE(scene::load_scene(dir / "t.json").settings.transparent);
    RenderOptions o;
    EXPECT_TRUE(resolve_options(scene::load_scene(dir / "t.json"), o).transparent);
    test::write_file(dir / "bad.json", R"({"render": {"transparent": "yes"}})");
    test::expect_error_message([&] { scene::load_scene(dir / "bad.json"); }, {"bad.json", "render.transparent"});

    const std::string gltf_head = R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [], "extras": )";
    test::write_file(dir / "t.gltf", gltf_head + R"({"transparent": true}}]})");
    EXPECT_TRUE(scene::load_scene(dir / "t.gltf").settings.transparent);
    test::write_file(dir / "f.gltf", gltf_head + R"({"spp": 4}}]})");
    EXPECT_FALSE(scene::load_scene(dir / "f.gltf").settings.transparent);
    test::write_file(dir / "bad.gltf", gltf_head + R"({"transparent": 1}}]})");
    test::expect_error_message([&] { scene::load_scene(dir / "bad.gltf"); }, {"bad.gltf", "extras.transparent"});
}

// `nerfpt render --transparent --aov ... --aov-files`: the EXR's channels by name, the PNG's alpha, the files
// beside it hold the layers.
TEST(Film, RenderCommandWritesNamedLayers) {
    if (!fs::exists(test::cli_binary())) GTEST_SKIP() << "nerfpt binary not built: " << test::cli_binary();
    const fs::path dir = test::temp_dir();
    test::write_file(dir / "quad.obj", "v -5 -5 0\nv 0.4 -5 0\nv 0.4 5 0\nv -5 5 0\nf 1 2 3\nf 1 3 4\n");
    test::write_file(dir / "scene.json", R"({"include": ["quad.obj"], "background": [0.5, 0.5, 0.5],
        "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "yfov_deg": 60}})");
    const fs::path out = dir / "out.exr";
    ASSERT_EQ(test::run_cli({"render", (dir / "scene.json").string(), "-o", out.string(), "--res", "24x16", "--spp",
                             "2", "--backend", "cpu", "--transparent", "--aov", "depth,albedo,normal", "--aov-files",
                             "-q"},
                            dir / "log"),
              0)
        << test::read_text(dir / "log");
    std::set<std::string> names;
    {
        Imf::InputFile f(out.string().c_str());
        for (auto c = f.header().channels().begin(); c != f.header().channels().end(); ++c) names.insert(c.name());
    }
    EXPECT_EQ(names, (std::set<std::string>{"R", "G", "B", "A", "albedo.R", "albedo.G", "albedo.B", "normal.X",
                                            "normal.Y", "normal.Z", "depth.Z"}));
    const Image rgba = read_image(out);
    EXPECT_EQ(rgba.channels, 4);
    const Image png = read_image(dir / "out.png");
    EXPECT_EQ(png.channels, 4);
    EXPECT_EQ(png.at(23, 8)[3], 0.0f);  // right of the quad: transparent
    EXPECT_EQ(png.at(2, 8)[3], 1.0f);

    // The files beside it: OUT.albedo.exr and OUT.normal.exr as RGB, OUT.depth.exr as Y (any EXR reader's image),
    // holding the layers of OUT.exr.
    const Image albedo = read_image(dir / "out.albedo.exr"), normal = read_image(dir / "out.normal.exr");
    const Image depth = read_image(dir / "out.depth.exr");
    ASSERT_EQ(albedo.channels, 3);
    ASSERT_EQ(normal.channels, 3);
    test::expect_near(albedo.rgb(4, 8), Vec3(1.0f), 1e-6f);  // the OBJ's default material is white
    test::expect_near(normal.rgb(4, 8), Vec3(0.0f, 0.0f, 1.0f), 1e-6f);
    EXPECT_GT(depth.rgb(4, 8).x, 3.0f);  // the quad at distance 3 along the axis, off the axis a little further
    EXPECT_LT(depth.rgb(4, 8).x, 3.5f);
    EXPECT_EQ(depth.rgb(23, 8).x, std::numeric_limits<float>::infinity());
    test::expect_near(albedo.rgb(23, 8), Rgb(0.0f), 0.0f);
    const std::pair<const Image*, std::vector<std::string>> layers[] = {
        {&albedo, {"albedo.R", "albedo.G", "albedo.B"}},
        {&normal, {"normal.X", "normal.Y", "normal.Z"}},
        {&depth, {"depth.Z"}}};  // read_image spreads the depth file's Y over R, G, B
    for (const auto& [image, channel_names] : layers) {
        const size_t n = channel_names.size();
        Image layer(24, 16, int(n));
        Imf::InputFile f(out.string().c_str());
        Imf::FrameBuffer fb;
        for (size_t c = 0; c < n; ++c)
            fb.insert(channel_names[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(layer.pixels.data() + c),
                                                   n * sizeof(float), n * sizeof(float) * 24));
        f.setFrameBuffer(fb);
        f.readPixels(0, 15);
        for (size_t i = 0; i < size_t(24 * 16); ++i)
            for (size_t c = 0; c < n; ++c)
                ASSERT_EQ(layer.pixels[n * i + c], image->pixels[3 * i + c]) << channel_names[c] << " pixel " << i;
    }
}

}  // namespace
}  // namespace npt::render
