// EXPERIMENT (not final): why a baked grid renders darker than the model it comes from.
// Usage: bake_colour_bench MODEL.npt OUT_DIR [RES...]
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bake/bake_grid.h"
#include "bake/grid_writers.h"
#include "core/image_io.h"
#include "core/srgb.h"
#include "nerf/model_file.h"
#include "nerf/nerf_placement.h"
#include "render/renderer.h"
#include "scene/scene.h"

using namespace npt;
namespace fs = std::filesystem;

namespace {

int g_spp = 16, g_size = 128;

Vec3 g_eye(0.0f, 0.6f, 2.6f);

Image render_file(const fs::path& dir, const std::string& file, uint64_t seed) {
    const fs::path scene_path = dir / ("scene_" + file + ".json");
    std::ofstream(scene_path) << fmt::format(
        R"({{"camera": {{"position": [{}, {}, {}], "look_at": [0, 0, 0], "yfov_deg": 45}},
 "background": [0, 0, 0], "render": {{"width": {}, "height": {}, "spp": {}, "max_depth": 1}},
 "volumes": [{{"file": "{}", "rotation": [-0.70710678, 0, 0, 0.70710678]}}]}})",
        g_eye.x, g_eye.y, g_eye.z, g_size, g_size, g_spp, file);
    const scene::Scene s = scene::load_scene(scene_path);
    render::RenderOptions o;
    o.seed = seed;
    return render::render(s, render::resolve_options(s, o));
}

// Object pixels: where the reference is brighter than 2% of its brightest pixel (sum of channels).
std::vector<uint8_t> object_mask(const Image& ref) {
    float mx = 0;
    for (int y = 0; y < ref.height; ++y)
        for (int x = 0; x < ref.width; ++x) {
            const Rgb c = ref.rgb(x, y);
            mx = std::max(mx, c.x + c.y + c.z);
        }
    std::vector<uint8_t> m(size_t(ref.width) * size_t(ref.height));
    for (int y = 0; y < ref.height; ++y)
        for (int x = 0; x < ref.width; ++x) {
            const Rgb c = ref.rgb(x, y);
            m[size_t(y) * size_t(ref.width) + size_t(x)] = (c.x + c.y + c.z) > 0.02f * mx;
        }
    return m;
}

// Sum over object pixels of img / sum of ref (all channels).
double ratio(const Image& img, const Image& ref, const std::vector<uint8_t>& mask) {
    double a = 0, b = 0;
    for (int y = 0; y < ref.height; ++y)
        for (int x = 0; x < ref.width; ++x) {
            if (!mask[size_t(y) * size_t(ref.width) + size_t(x)]) continue;
            const Rgb p = img.rgb(x, y), q = ref.rgb(x, y);
            a += p.x + p.y + p.z;
            b += q.x + q.y + q.z;
        }
    return a / b;
}

Rgb lin(Rgb s) { return Rgb(srgb_to_linear(s.x), srgb_to_linear(s.y), srgb_to_linear(s.z)); }
Rgb enc(Rgb s) { return Rgb(linear_to_srgb(s.x), linear_to_srgb(s.y), linear_to_srgb(s.z)); }

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: %s MODEL.npt OUT_DIR [RES...]\n", argv[0]);
        return 2;
    }
    if (const char* s = std::getenv("SPP")) g_spp = std::atoi(s);
    if (const char* s = std::getenv("SIZE")) g_size = std::atoi(s);
    const fs::path dir = argv[2];
    fs::create_directories(dir);
    nerf::NerfModel model = nerf::load_model(argv[1]);
    if (const char* tj = std::getenv("VIEWDIRS_FROM")) {  // a model written before view directions were stored
        const auto j = nlohmann::json::parse(std::ifstream(tj));
        for (const auto& f : j["frames"]) {
            const auto& m = f["transform_matrix"];
            const Vec3 fwd(-m[0][2].get<float>(), -m[1][2].get<float>(), -m[2][2].get<float>());
            model.view_directions.push_back(normalize(model.world_to_model.transform_vector(fwd)));
        }
    }
    nerf::save_model(dir / "m.npt", model, false);
    std::vector<int> resolutions;
    for (int i = 3; i < argc; ++i) resolutions.push_back(std::atoi(argv[i]));
    if (resolutions.empty()) resolutions = {128, 256};

    // Views: the default one, or every VIEW_STRIDE-th training camera (lego: world / 1.515 = local; scene =
    // (x, z, -y) of local).
    std::vector<Vec3> eyes{g_eye};
    if (const char* vs = std::getenv("VIEW_STRIDE")) {
        eyes.clear();
        const auto j = nlohmann::json::parse(std::ifstream(std::getenv("TRANSFORMS")));
        int n = 0;
        for (const auto& f : j["frames"]) {
            if (n++ % std::atoi(vs)) continue;
            const auto& m = f["transform_matrix"];
            const Vec3 p(m[0][3].get<float>(), m[1][3].get<float>(), m[2][3].get<float>());
            eyes.push_back(Vec3(p.x, p.z, -p.y) / 1.515f);
        }
    }
    // Constant-colour copy: the colour MLP's last layer zeroed (bias-free: sigmoid(0) = 0.5 everywhere).
    nerf::NerfModel flat = model;
    {
        const nerf::NerfLayout L = flat.layout();
        const size_t begin = L.color_offset + L.color.layer_offset(L.color.hidden_layers);
        const size_t end = L.color_offset + L.color.param_count();
        for (size_t i = begin; i < end; ++i) flat.params[i] = 0.0f;
    }
    nerf::save_model(dir / "flat.npt", flat, false);
    std::vector<Image> direct, flat_direct;
    std::vector<std::vector<uint8_t>> mask, flat_mask;
    for (const Vec3& e : eyes) {
        g_eye = e;
        direct.push_back(render_file(dir, "m.npt", 1));
        write_png(dir / fmt::format("direct_view{}.png", direct.size() - 1), direct.back());
        mask.push_back(object_mask(direct.back()));
        flat_direct.push_back(render_file(dir, "flat.npt", 1));
        flat_mask.push_back(object_mask(flat_direct.back()));
        const Image d2 = render_file(dir, "m.npt", 2);
        std::printf("view (%.2f %.2f %.2f): seed 2 / seed 1 %.4f\n", e.x, e.y, e.z, ratio(d2, direct.back(), mask.back()));
    }
    const Vec3 cam_dir = normalize(Vec3(-eyes[0].x, eyes[0].z, -eyes[0].y));

    // Directions (training-world axes) of 16 sphere directions and of the training cameras towards the origin.
    std::vector<Vec3> sphere_dirs;
    for (const Vec3& d : bake::average_directions()) sphere_dirs.push_back(nerf::model_to_world_axes(d));
    std::vector<Vec3> cam_dirs;
    if (const char* tj = std::getenv("TRANSFORMS")) {
        const auto j = nlohmann::json::parse(std::ifstream(tj));
        int stride = std::getenv("CAM_STRIDE") ? std::atoi(std::getenv("CAM_STRIDE")) : 4;
        int n = 0;
        for (const auto& f : j["frames"]) {
            if (n++ % stride) continue;
            const auto& m = f["transform_matrix"];
            const Vec3 pos(m[0][3].get<float>(), m[1][3].get<float>(), m[2][3].get<float>());
            cam_dirs.push_back(normalize(-pos));
        }
        std::printf("%zu camera directions\n", cam_dirs.size());
    }

    for (int res : resolutions) {
        auto row = [&](const std::string& name, const bake::BakedGrid& g, bool flat_ref = false) {
            const std::string file = fmt::format("{}_{}.vdb", name, res);
            bake::write_vdb(dir / file, g);
            double sum = 0, lo = 1e9, hi = -1e9;
            std::string per;
            for (size_t v = 0; v < eyes.size(); ++v) {
                g_eye = eyes[v];
                const Image img = render_file(dir, file, 1);
                write_png(dir / fmt::format("{}_view{}.png", file, v), img);
                const double r = flat_ref ? ratio(img, flat_direct[v], flat_mask[v]) : ratio(img, direct[v], mask[v]);
                sum += r;
                lo = std::min(lo, r);
                hi = std::max(hi, r);
                per += fmt::format(" {:.3f}", r);
            }
            std::printf("%4d  %-26s mean %.4f  min %.4f  max %.4f |%s\n", res, name.c_str(), sum / eyes.size(), lo, hi, per.c_str());
            std::fflush(stdout);
        };
        bake::BakeSettings bs;
        bs.resolution = res;
        row("flat_opacity", bake::bake_model(flat, bs), true);
        const bake::BakedGrid today = bake::bake_model(model, bs);
        row("today_avg16_srgb", today);
        if (eyes.size() == 1) {
        bake::BakeSettings cs = bs;
        cs.direction = cam_dir;
        row("camera_dir", bake::bake_model(model, cs));
        }

        // Dense σ of the bake (density voxels only) for visibility marches.
        const auto& L = today.layout;
        const int nx = L.dims[0], ny = L.dims[1], nz = L.dims[2];
        std::vector<float> dense(L.voxel_count(), 0.0f);
        for (size_t v = 0; v < today.size(); ++v)
            if (today.has_density[v])
                dense[(size_t(today.coords[3 * v + 2]) * size_t(ny) + size_t(today.coords[3 * v + 1])) * size_t(nx) +
                      size_t(today.coords[3 * v])] = today.sigma[v];
        const float voxel_model = L.model_per_local * 2.0f / float(std::max(nx, std::max(ny, nz)));
        // Transmittance from voxel v's centre back along -d (world axes = local axes) out of the box, starting
        // one voxel away, half-voxel steps, nearest voxel.
        auto visibility = [&](size_t v, Vec3 d) {
            const float h = 0.5f;
            float tau = 0;
            for (float t = 1.0f;; t += h) {
                const float x = float(today.coords[3 * v]) - d.x * t, y = float(today.coords[3 * v + 1]) - d.y * t,
                            z = float(today.coords[3 * v + 2]) - d.z * t;
                const int i = int(std::lround(x)), j = int(std::lround(y)), k = int(std::lround(z));
                if (i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz) break;
                tau += dense[(size_t(k) * size_t(ny) + size_t(j)) * size_t(nx) + size_t(i)] * h * voxel_model;
                if (tau > 20) break;
            }
            return std::exp(-tau);
        };
        auto per_dir_colors = [&](const std::vector<Vec3>& ds) {
            std::vector<std::vector<Rgb>> out;
            for (const Vec3& d : ds) {
                bake::BakeSettings s = bs;
                s.direction = d;
                out.push_back(bake::bake_model(model, s).color);
            }
            return out;
        };
        auto combine = [&](const std::vector<Vec3>& ds, const std::vector<std::vector<Rgb>>& cols, auto keep,
                           bool linear, bool vis) {
            bake::BakedGrid g = today;
            for (size_t v = 0; v < g.size(); ++v) {
                Rgb sum(0.0f);
                double wsum = 0;
                for (size_t d = 0; d < ds.size(); ++d) {
                    if (!keep(ds[d])) continue;
                    const float w = (vis ? visibility(v, ds[d]) : 1.0f) + 1e-6f;
                    sum += (linear ? lin(cols[d][v]) : cols[d][v]) * w;
                    wsum += w;
                }
                g.color[v] = linear ? enc(sum / float(wsum)) : sum / float(wsum);
            }
            return g;
        };
        auto all = [](Vec3) { return true; };
        auto down = [](Vec3 d) { return d.z < 0.0f; };
        {
            const auto cols = per_dir_colors(sphere_dirs);
            row("sphere16_linear", combine(sphere_dirs, cols, all, true, false));
            row("sphere16_down_srgb", combine(sphere_dirs, cols, down, false, false));
            row("sphere16_vis_srgb", combine(sphere_dirs, cols, all, false, true));
            row("sphere16_vis_linear", combine(sphere_dirs, cols, all, true, true));
            row("sphere16_down_vis_linear", combine(sphere_dirs, cols, down, true, true));
        }
        if (!cam_dirs.empty()) {
            const auto cols = per_dir_colors(cam_dirs);
            row("cams_srgb", combine(cam_dirs, cols, all, false, false));
            row("cams_linear", combine(cam_dirs, cols, all, true, false));
            row("cams_vis_linear", combine(cam_dirs, cols, all, true, true));
        }
    }
    return 0;
}
