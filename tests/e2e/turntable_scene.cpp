#include "turntable_scene.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>

#include "core/error.h"
#include "core/image_io.h"
#include "core/srgb.h"
#include "render/renderer.h"

namespace npt::test {
namespace fs = std::filesystem;

namespace {

constexpr double k_deg = std::numbers::pi / 180.0;
const Vec3 k_target{0.0f, 0.5f, 0.0f};  // centre of the box

// HSV (h in degrees, s and v in [0,1]) to sRGB-encoded RGB.
Rgb hsv_to_rgb(float h, float s, float v) {
    const float c = v * s, hp = std::fmod(h / 60.0f, 6.0f),
                x = c * (1.0f - std::fabs(std::fmod(hp, 2.0f) - 1.0f));
    Rgb rgb = hp < 1   ? Rgb(c, x, 0)
              : hp < 2 ? Rgb(x, c, 0)
              : hp < 3 ? Rgb(0, c, x)
              : hp < 4 ? Rgb(0, x, c)
              : hp < 5 ? Rgb(x, 0, c)
                       : Rgb(c, 0, x);
    const float m = v - c;
    return Rgb(rgb.x + m, rgb.y + m, rgb.z + m);
}

// Random overlapping rectangles, colours from `colour(rng)`: corners everywhere, no repetition.
// Rectangle sides are side/max_div .. side/min_div texels.
template <class ColourFn>
scene::Texture random_rectangles(const std::string& name, int side, int count, uint32_t seed, ColourFn colour,
                                 int min_div = 8, int max_div = 64) {
    std::mt19937 rng(seed);
    std::vector<Rgb> srgb(size_t(side) * size_t(side), colour(rng));
    std::uniform_int_distribution<int> pos(0, side - 1), size(side / max_div, side / min_div);
    for (int k = 0; k < count; ++k) {
        const int x0 = pos(rng), y0 = pos(rng), w = size(rng), h = size(rng);
        const Rgb c = colour(rng);
        for (int y = y0; y < std::min(side, y0 + h); ++y)
            for (int x = x0; x < std::min(side, x0 + w); ++x) srgb[size_t(y) * size_t(side) + size_t(x)] = c;
    }
    scene::Texture t;
    t.name = name;
    t.width = t.height = side;
    t.rgba.resize(srgb.size() * 4);
    for (size_t i = 0; i < srgb.size(); ++i) {
        t.rgba[4 * i + 0] = srgb_to_linear(srgb[i].x);
        t.rgba[4 * i + 1] = srgb_to_linear(srgb[i].y);
        t.rgba[4 * i + 2] = srgb_to_linear(srgb[i].z);
        t.rgba[4 * i + 3] = 1.0f;
    }
    return t;
}

scene::Material diffuse(const std::string& name, int texture) {
    scene::Material m;
    m.name = name;
    m.base_color_texture = texture;
    m.metallic = 0.0f;
    m.specular = 0.0f;
    return m;
}

// One quad (two triangles) with its own uv rectangle.
void add_quad(scene::Mesh& mesh, Vec3 origin, Vec3 edge_u, Vec3 edge_v, Vec2 uv0, Vec2 uv1) {
    const uint32_t base = uint32_t(mesh.positions.size());
    const Vec3 n = normalize(cross(edge_u, edge_v));
    const Vec3 p[4] = {origin, origin + edge_u, origin + edge_u + edge_v, origin + edge_v};
    const Vec2 uv[4] = {{uv0.x, uv1.y}, {uv1.x, uv1.y}, {uv1.x, uv0.y}, {uv0.x, uv0.y}};
    for (int i = 0; i < 4; ++i) {
        mesh.positions.push_back(p[i]);
        mesh.normals.push_back(n);
        mesh.uvs.push_back(uv[i]);
    }
    for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) mesh.indices.push_back(base + i);
}

}  // namespace

scene::Scene make_turntable_scene(bool rich_texture) {
    scene::Scene s;
    // The box: saturated oranges and reds of varying brightness (one hue band for the subject mask).
    const auto box_colour = [](std::mt19937& rng) {
        std::uniform_real_distribution<float> h(5.0f, 40.0f), sat(0.6f, 1.0f), v(0.25f, 1.0f);
        return hsv_to_rgb(h(rng), sat(rng), v(rng));
    };
    // The floor: 2048 texels over 12 units, ~170 per unit, finer than the pixels that see it, so that the
    // floor near the camera stays sharp (SIFT finds nothing on a magnified, blurred texture).
    const auto floor_colour = [](std::mt19937& rng) {
        std::uniform_real_distribution<float> h(180.0f, 240.0f), sat(0.0f, 0.15f), v(0.15f, 0.85f);
        return hsv_to_rgb(h(rng), sat(rng), v(rng));
    };
    if (rich_texture) {
        // Rectangles of 8-64 texels, twice the texel density: corners every few pixels at 540x960.
        s.textures.push_back(random_rectangles("box", 2048, 60000, 7, box_colour, 32, 256));
        s.textures.push_back(random_rectangles("floor", 4096, 250000, 11, floor_colour, 64, 512));
    } else {
        s.textures.push_back(random_rectangles("box", 768, 2500, 7, box_colour));
        s.textures.push_back(random_rectangles("floor", 2048, 16000, 11, floor_colour));
    }
    s.materials = {diffuse("box", 0), diffuse("floor", 1)};

    // A box 1.2 x 1.0 x 0.8 standing on the floor; each face its own sixth of the texture (3 x 2 atlas), so
    // no two faces look alike.
    scene::Mesh box;
    box.name = "box";
    box.material = 0;
    const float hx = 0.6f, hz = 0.4f, top = 1.0f;
    const Vec3 c[8] = {{-hx, 0, -hz}, {hx, 0, -hz}, {hx, top, -hz}, {-hx, top, -hz},
                       {-hx, 0, hz},  {hx, 0, hz},  {hx, top, hz},  {-hx, top, hz}};
    struct Face {
        int o, u, v;
    };
    const Face faces[6] = {{4, 5, 7}, {1, 0, 2}, {5, 1, 6}, {0, 4, 3}, {7, 6, 3}, {0, 1, 4}};
    for (int f = 0; f < 6; ++f) {
        const Vec2 uv0{float(f % 3) / 3.0f, float(f / 3) / 2.0f};
        const Vec2 uv1{uv0.x + 1.0f / 3.0f, uv0.y + 0.5f};
        add_quad(box, c[faces[f].o], c[faces[f].u] - c[faces[f].o], c[faces[f].v] - c[faces[f].o], uv0, uv1);
    }
    s.meshes.push_back(box);
    scene::Mesh floor;
    floor.name = "floor";
    floor.material = 1;
    add_quad(floor, Vec3(-6, 0, 6), Vec3(12, 0, 0), Vec3(0, 0, -12), Vec2(0, 0), Vec2(1, 1));
    s.meshes.push_back(floor);

    // A sun from the upper left and a dim sky: shading that changes with the face but no black sides.
    scene::PunctualLight sun;
    sun.name = "sun";
    sun.type = scene::PunctualType::Directional;
    sun.direction = normalize(Vec3(0.4f, -1.0f, -0.3f));
    sun.intensity = Rgb(2.5f);
    s.lights.push_back(sun);
    s.environment.color = Rgb(0.45f, 0.5f, 0.55f);
    s.settings.max_depth = 2;
    return s;
}

scene::Camera turntable_camera(const TurntableSettings& st, int frame) {
    const double t = double(frame) / double(st.frames);
    const double azimuth = 2.0 * std::numbers::pi * st.turns * t;
    const double elevation =
        (st.elevation_low_deg + (st.elevation_high_deg - st.elevation_low_deg) * t) * k_deg;
    scene::Camera cam;
    cam.name = fmt::format("frame_{:05}", frame);
    const Vec3 offset(float(std::cos(elevation) * std::sin(azimuth)), float(std::sin(elevation)),
                      float(std::cos(elevation) * std::cos(azimuth)));
    cam.position = k_target + offset * float(st.distance);
    cam.forward = normalize(k_target - cam.position);
    cam.right = normalize(cross(cam.forward, Vec3(0, 1, 0)));
    cam.up = cross(cam.right, cam.forward);
    cam.yfov = float(st.fov_y_deg * k_deg);
    return cam;
}

Mat4 opengl_camera_to_world(const scene::Camera& cam) {
    Mat4 m;
    const Vec3 cols[4] = {cam.right, cam.up, cam.forward * -1.0f, cam.position};
    for (int c = 0; c < 4; ++c) {
        m.m[0][c] = cols[c].x;
        m.m[1][c] = cols[c].y;
        m.m[2][c] = cols[c].z;
        m.m[3][c] = c == 3 ? 1.0 : 0.0;
    }
    return m;
}

void render_turntable_video(const TurntableSettings& st, const fs::path& folder, const fs::path& video) {
    fs::create_directories(folder);
    scene::Scene s = make_turntable_scene(st.rich_texture);
    render::RenderOptions opt;
    opt.width = st.width;
    opt.height = st.height;
    opt.spp = st.spp;
    for (int k = 0; k < st.frames; ++k) {
        s.cameras = {turntable_camera(st, k)};
        s.camera = 0;
        const render::RenderOptions resolved = render::resolve_options(s, opt);
        write_png(folder / fmt::format("render_{:05}.png", k), render::render(s, resolved));
    }
    // yuv420p at a high quality: what a phone writes, with mild compression.
    const std::string cmd = fmt::format(
        "ffmpeg -nostdin -v error -y -framerate {} -i '{}/render_%05d.png' -c:v libx264 -crf 14 -pix_fmt "
        "yuv420p "
        "'{}' 2>'{}/ffmpeg.log'",
        st.fps, folder.string(), video.string(), folder.string());
    if (std::system(cmd.c_str()) != 0)
        throw Error("ffmpeg could not encode the turntable; see " + (folder / "ffmpeg.log").string());
}

void write_true_transforms(const TurntableSettings& st, const fs::path& json) {
    nlohmann::json root;
    const double fy = 0.5 * st.height / std::tan(0.5 * st.fov_y_deg * k_deg);
    root["fl_x"] = fy;
    root["fl_y"] = fy;
    root["cx"] = 0.5 * st.width;
    root["cy"] = 0.5 * st.height;
    root["w"] = st.width;
    root["h"] = st.height;
    root["frames"] = nlohmann::json::array();
    for (int k = 0; k < st.frames; ++k) {
        const Mat4 m = opengl_camera_to_world(turntable_camera(st, k));
        nlohmann::json rows = nlohmann::json::array();
        for (int r = 0; r < 4; ++r) rows.push_back({m.m[r][0], m.m[r][1], m.m[r][2], m.m[r][3]});
        root["frames"].push_back(
            {{"file_path", fmt::format("frame_{:05}.png", k)}, {"transform_matrix", rows}});
    }
    std::ofstream(json) << root.dump(2) << "\n";
}

}  // namespace npt::test
