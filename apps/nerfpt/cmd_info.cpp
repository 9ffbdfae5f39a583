#include "cmd_info.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/error.h"
#include "media/volume_set.h"
#include "nerf/model_file.h"
#include "nerf/relight/relight_env.h"
#include "scene/scene.h"

namespace npt::cli {
namespace {

using scene::Material;
using scene::Scene;

// Long lists are cut here: `info` is for a quick look, not a dump.
constexpr size_t k_max_listed = 24;

// + 0.0f turns -0 into 0, which reads better.
std::string vec(Vec3 v) {
    return fmt::format("({:.3g}, {:.3g}, {:.3g})", v.x + 0.0f, v.y + 0.0f, v.z + 0.0f);
}
float degrees(float radians) { return radians * 180.0f / k_pi; }

std::string texture_name(const Scene& s, int index) {
    if (index < 0 || size_t(index) >= s.textures.size()) return "";
    const auto& t = s.textures[size_t(index)];
    return fmt::format(" texture '{}' {}x{}", t.name, t.width, t.height);
}

// The kind decides which parameters matter; the same order as the BSDF selection in render/.
std::string material_kind(const Material& m) {
    if (m.is_volume) return "volume";
    if (!is_black(m.emission) || m.emissive_texture >= 0) return "emissive";
    if (m.transmission > 0) return "glass";
    if (m.metallic >= 0.5f) return "metal";
    return "diffuse";
}

std::string material_params(const Scene& s, const Material& m) {
    const std::string kind = material_kind(m);
    std::string p;
    if (kind == "volume") return "NeRF placeholder, not drawn as a surface";
    if (kind == "emissive") p += "emission " + vec(m.emission) + texture_name(s, m.emissive_texture) + ", ";
    if (kind == "glass") p += fmt::format("transmission {:.3g}, ior {:.3g}, ", m.transmission, m.ior);
    p += "base " + vec(m.base_color) + texture_name(s, m.base_color_texture);
    p += fmt::format(", roughness {:.3g}", m.roughness);
    if (kind == "metal" || (m.metallic > 0 && m.metallic < 1))
        p += fmt::format(", metallic {:.3g}", m.metallic);
    if (m.metallic_roughness_texture >= 0)
        p += ", metal/rough" + texture_name(s, m.metallic_roughness_texture);
    if (kind == "diffuse" && m.specular != 1.0f) p += fmt::format(", specular {:.3g}", m.specular);
    if (m.normal_texture >= 0) p += ", normal map" + texture_name(s, m.normal_texture);
    if (m.double_sided) p += ", double-sided";
    return p;
}

std::string material_name(const Scene& s, int index) {
    if (index < 0 || size_t(index) >= s.materials.size()) return "?";
    return s.materials[size_t(index)].name.empty() ? "#" + std::to_string(index)
                                                   : s.materials[size_t(index)].name;
}

void print_meshes(const Scene& s) {
    fmt::print("meshes     {} ({} triangles)\n", s.meshes.size(), s.triangle_count());
    for (size_t i = 0; i < s.meshes.size() && i < k_max_listed; ++i) {
        const auto& m = s.meshes[i];
        fmt::print("  {:<20} {:>9} tris  material '{}'{}\n",
                   m.name.empty() ? "#" + std::to_string(i) : m.name, m.triangle_count(),
                   material_name(s, m.material), m.uvs.empty() ? "" : ", uv");
    }
    if (s.meshes.size() > k_max_listed) fmt::print("  ... and {} more\n", s.meshes.size() - k_max_listed);
}

void print_materials(const Scene& s) {
    fmt::print("materials  {}\n", s.materials.size());
    for (size_t i = 0; i < s.materials.size() && i < k_max_listed; ++i) {
        const auto& m = s.materials[i];
        fmt::print("  {:<20} {:<8} {}\n", material_name(s, int(i)), material_kind(m), material_params(s, m));
    }
    if (s.materials.size() > k_max_listed)
        fmt::print("  ... and {} more\n", s.materials.size() - k_max_listed);
}

void print_lights(const Scene& s) {
    int by_type[3] = {0, 0, 0};
    for (const auto& l : s.lights) ++by_type[int(l.type)];
    size_t emissive_meshes = 0, emissive_tris = 0;
    for (const auto& m : s.meshes) {
        if (m.material < 0 || size_t(m.material) >= s.materials.size()) continue;
        const auto& mat = s.materials[size_t(m.material)];
        if (!mat.is_volume && (!is_black(mat.emission) || mat.emissive_texture >= 0)) {
            ++emissive_meshes;
            emissive_tris += m.triangle_count();
        }
    }
    fmt::print(
        "lights     {} punctual ({} point, {} spot, {} directional), {} emissive meshes ({} triangles)\n",
        s.lights.size(), by_type[0], by_type[1], by_type[2], emissive_meshes, emissive_tris);
    for (size_t i = 0; i < s.lights.size() && i < k_max_listed; ++i) {
        const auto& l = s.lights[i];
        const std::string name = l.name.empty() ? "#" + std::to_string(i) : l.name;
        switch (l.type) {
            case scene::PunctualType::Point:
                fmt::print("  point       '{}' at {}, intensity {} cd\n", name, vec(l.position),
                           vec(l.intensity));
                break;
            case scene::PunctualType::Spot:
                fmt::print("  spot        '{}' at {} toward {}, intensity {} cd, cone {:.1f}..{:.1f} deg\n",
                           name, vec(l.position), vec(l.direction), vec(l.intensity), degrees(l.inner_cone),
                           degrees(l.outer_cone));
                break;
            case scene::PunctualType::Directional:
                fmt::print("  directional '{}' toward {}, {} lux\n", name, vec(l.direction),
                           vec(l.intensity));
                break;
        }
    }
    const auto& env = s.environment;
    if (env.texture >= 0)
        fmt::print("  environment map{}, strength {:.3g}, rotated {:.1f} deg about +Y\n",
                   texture_name(s, env.texture), env.strength, degrees(env.rotation_y));
    else if (env.is_black())
        fmt::print("  environment none (black)\n");
    else
        fmt::print("  environment constant {}\n", vec(env.color));
}

void print_camera(const Scene& s) {
    if (s.camera < 0 || size_t(s.camera) >= s.cameras.size()) {
        fmt::print("camera     none in the file (a default view is made)\n");
        return;
    }
    const auto& c = s.cameras[size_t(s.camera)];
    fmt::print("camera     '{}' ({} of {}) at {}, forward {}, up {}, yfov {:.1f} deg, aspect {}\n", c.name,
               s.camera + 1, s.cameras.size(), vec(c.position), vec(c.forward), vec(c.up), degrees(c.yfov),
               c.aspect > 0 ? fmt::format("{:.3f}", c.aspect) : std::string("from the image"));
    if (s.cameras.size() > 1) {
        std::string names;
        for (const auto& other : s.cameras) names += (names.empty() ? "'" : ", '") + other.name + "'";
        fmt::print("  available (--camera NAME): {}\n", names);
    }
}

// How the renderer will shade a volume (docs/formats.md, "shading"): a model without an explicit shading is
// loaded to see whether it is relightable. A volume the renderer would refuse says why.
std::string volume_shading(const Scene& s, const scene::VolumeInstance& v) {
    const std::filesystem::path& declared = v.declared_in.empty() ? s.source : v.declared_in;
    const std::string where = declared.string() + ": node '" + v.name + "'";
    try {
        const media::VolumeDesc d = media::parse_volume_desc(v.extras_json, where);
        std::filesystem::path file = d.file;
        if (file.is_relative()) file = declared.parent_path() / file;
        if (file.extension() != ".npt") {
            if (d.shading == media::VolumeShading::Relit)
                return "invalid: \"relit\" is for NeRF models (.npt) only";
            return "emissive (a grid)";
        }
        if (d.shading == media::VolumeShading::Emissive) return "emissive";
        const bool relit = media::volume_is_relit(d, nerf::load_model(file).relightable(), where);
        if (d.shading == media::VolumeShading::Relit) return "relit";
        return relit ? "relit (the default for a relightable model)"
                     : "emissive (the default: the model is not relightable)";
    } catch (const Error& e) {
        return std::string("invalid: ") + e.what();
    }
}

void print_volumes(const Scene& s) {
    fmt::print("volumes    {}\n", s.volumes.size());
    for (const auto& v : s.volumes) {
        Vec3 lo(INFINITY), hi(-INFINITY);
        for (int corner = 0; corner < 8; ++corner) {
            const Vec3 p(corner & 1 ? v.local_max.x : v.local_min.x,
                         corner & 2 ? v.local_max.y : v.local_min.y,
                         corner & 4 ? v.local_max.z : v.local_min.z);
            const Vec3 w = v.local_to_world.transform_point(p);
            lo = vmin(lo, w);
            hi = vmax(hi, w);
        }
        const auto& m = v.local_to_world.m;
        fmt::print("  '{}' world bounds {} .. {}, translation {}\n", v.name, vec(lo), vec(hi),
                   vec(Vec3(float(m[0][3]), float(m[1][3]), float(m[2][3]))));
        fmt::print("    extras {}\n", v.extras_json.empty() ? "(none)" : v.extras_json);
        fmt::print("    shading {}\n", volume_shading(s, v));
    }
}

}  // namespace

CLI::App* add_info_command(CLI::App& app, InfoArgs& args) {
    CLI::App* cmd =
        app.add_subcommand("info", "Print what a scene or a model file holds");
    cmd->footer(
        "For a scene: meshes, materials, lights, camera, volumes. For a model (.npt): its config, training\n"
        "progress, occupancy and where its content lies in model space and in the training world (useful to\n"
        "place it in a volume cube, docs/formats.md).\n"
        "Examples: nerfpt info scenes/example/scene.gltf\n"
        "          nerfpt info lego.npt");
    cmd->add_option("SCENE", args.scene, "Scene file (.gltf, .glb, .obj, .json) or model file (.npt)")
        ->required();
    cmd->add_option("--camera", args.camera,
                    "Camera to describe, by glTF node or camera name (default: the first)");
    return cmd;
}

namespace {

// The per-image gains training.exposure_per_image learned: their range per channel, then each image's mean gain
// over the channels in the training set's order, ten to a line, so that a drift over the video shows.
void print_exposures(const nerf::ExposureState& e) {
    if (e.empty()) return;
    const nerf::ExposureRange r = nerf::exposure_range(e);
    fmt::print("  exposure per image ({} images): gain R {:.3f}..{:.3f}, G {:.3f}..{:.3f}, B {:.3f}..{:.3f}; "
               "mean gain per image:\n",
               e.log_gain.size(), r.lo.x, r.hi.x, r.lo.y, r.hi.y, r.lo.z, r.hi.z);
    for (size_t i = 0; i < e.log_gain.size(); ++i) {
        const Rgb g = nerf::exposure_gain(e, i);
        fmt::print("{}{:.3f}", i % 10 == 0 ? fmt::format("    {:4d}: ", i) : "", (g.x + g.y + g.z) / 3.0f);
        fmt::print("{}", i % 10 == 9 || i + 1 == e.log_gain.size() ? "\n" : " ");
    }
}

// Whether the model is relightable, and the capture light its relight stage estimated.
void print_relight(const nerf::NerfModel& m) {
    if (!m.relightable()) {
        fmt::print("relight    no: emissive only (train with --relightable to light it by a scene)\n");
        return;
    }
    const nerf::RelightFields& r = *m.relight;
    fmt::print("relight    yes: intrinsic grid {} levels x {}, 2^{} entries, MLP {}x{}; {} steps, {:.0f} s; {} diffuse\n",
               r.config.grid.levels, r.config.grid.features_per_level, r.config.grid.log2_table_size,
               r.config.hidden_layers, r.config.width, r.steps, r.seconds,
               r.config.diffuse == nerf::IntrinsicDiffuse::burley ? "Burley (Cycles v1)" : "layered");
    const nerf::CaptureEnvironment& env = r.capture_env;
    // Above and below the training world's horizon (+z up, as `poses` and NeRF-synthetic write it): the
    // images constrain the light's vertical profile least, so it is worth seeing (docs/relighting.md).
    const Mat4 model_to_world = m.world_to_model.inverse();
    Rgb mean(0.0f), sky(0.0f), ground(0.0f);
    double total = 0, best = -1, sky_w = 0, ground_w = 0;
    Vec3 best_dir(0.0f);
    for (int j = 0; j < env.height; ++j)
        for (int i = 0; i < env.width; ++i) {
            const Rgb& t = env.texels[size_t(j) * env.width + i];
            const float w = nerf::env_texel_solid_angle(env.width, env.height, j);
            mean += t * w;
            total += w;
            const Vec3 toward = model_to_world.transform_vector(nerf::env_texel_direction(env.width, env.height, i, j));
            if (toward.z >= 0.0f) {
                sky += t * w;
                sky_w += w;
            } else {
                ground += t * w;
                ground_w += w;
            }
            const double lum = 0.2126 * t.x + 0.7152 * t.y + 0.0722 * t.z;
            if (lum > best) {
                best = lum;
                best_dir = nerf::env_texel_direction(env.width, env.height, i, j);
            }
        }
    mean = mean / float(total);
    const Vec3 world_dir = normalize(model_to_world.transform_vector(best_dir));
    fmt::print("  capture light {}x{} environment, mean radiance {}, brightest toward {} (training world)\n",
               env.width, env.height, vec(mean), vec(world_dir));
    if (sky_w > 0 && ground_w > 0)
        fmt::print("  mean radiance above the horizon (training world +z) {}, below {}\n", vec(sky / float(sky_w)),
                   vec(ground / float(ground_w)));
    if (!r.exposure.empty()) {
        float lo = INFINITY, hi = 0;
        for (const Rgb& e : r.exposure) {
            lo = std::min(lo, e.x);
            hi = std::max(hi, e.x);
        }
        fmt::print("  exposures of {} images: {:.3f} .. {:.3f}\n", r.exposure.size(), lo, hi);
    }
}

// The object frame a capture stored (nerf/object_frame.h): where a `volume` cube puts the object.
void print_object(const nerf::NerfModel& m) {
    if (!m.object) {
        fmt::print("object     no object frame (not from `nerfpt capture`): a volume cube stretches the model's box "
                   "onto itself; place it with a crop (docs/formats.md)\n");
        return;
    }
    const nerf::ObjectFrame& f = *m.object;
    const char* units = f.metric ? "m" : "capture units";
    const Vec3 size = f.box_max - f.box_min;
    fmt::print("object     {:.3g} x {:.3g} x {:.3g} {} (width, depth, height): box x {:.3g}..{:.3g}, y {:.3g}..{:.3g}, "
               "z {:.3g}..{:.3g} in its frame (origin at the base centre on the supporting plane, +Z up)\n",
               size.x, size.y, size.z, units, f.box_min.x, f.box_max.x, f.box_min.y, f.box_max.y, f.box_min.z,
               f.box_max.z);
    const Mat4& o = f.object_to_world;
    const Vec3 up = normalize(o.transform_vector(Vec3(0, 0, 1)));
    fmt::print("  in the training world: base centre {}, up {}, {:.4g} {} per world unit\n",
               vec(o.transform_point(Vec3(0.0f))), vec(up), f.units_per_world(), f.metric ? "metres" : "units");
    fmt::print("  a volume cube with this model and an identity node stands it on y = 0 at the origin (Y up){}\n",
               f.metric ? ", at its real size" : " (no --height was given: capture units, not metres)");
    if (f.object_only)
        fmt::print("  isolated (nerfpt isolate): the object alone; eval and view show only its box, as a scene does\n");
}

// A model file: what it is, how far it was trained, and where its content lies (to place it in a scene).
int print_model_info(const std::string& path) {
    const nerf::NerfModel m = nerf::load_model(path);
    const nerf::NerfLayout l = m.layout();
    const auto& g = l.grid;
    fmt::print("model      {}\n", path);
    fmt::print("field      hash grid {} levels x {} features, 2^{} entries, base {}, finest {:.0f}; density MLP "
               "{}x{} -> {}, colour MLP {}x{} -> 3; {} parameters\n",
               g.levels, g.features_per_level, g.log2_table_size, g.base_resolution,
               m.config.encoding.finest_resolution * m.aabb_scale, m.config.density_mlp.hidden_layers,
               m.config.density_mlp.width, m.config.density_mlp.outputs, m.config.color_mlp.hidden_layers,
               m.config.color_mlp.width, l.total);
    if (m.training) {
        fmt::print("training   {} steps, {:.0f} s; optimizer state included (can --resume)\n",
                   m.training->adam.step, m.training->elapsed_seconds);
        print_exposures(m.training->exposure);
    }
    else
        fmt::print("training   no training state (render/evaluate only)\n");
    print_relight(m);
    fmt::print("occupancy  {} cascade(s) of {}^3, {:.1f}% occupied\n", m.occupancy.cascades(),
               m.occupancy.resolution(), 100.0 * m.occupancy.occupied_fraction());
    // Where the content is: the occupied cells of the finest cascade that has any, in model space and in the
    // training world (the transforms.json cameras' space).
    const nerf::OccupancyGridView v = m.occupancy.view();
    const int r = v.resolution;
    // Per axis, the 1st and 99th percentile of the occupied cells' centres: a few floaters near the box's faces
    // (common where few cameras look) would otherwise make the bounds the whole box.
    std::vector<float> coords[3];
    for (int c = 0; c < v.cascades && coords[0].empty(); ++c) {
        const float size = v.cascade_size(c), cell = size / float(r), base = 0.5f - 0.5f * size;
        for (int z = 0; z < r; ++z)
            for (int y = 0; y < r; ++y)
                for (int x = 0; x < r; ++x)
                    if (v.occupied[size_t(c) * r * r * r + x + size_t(y) * r + size_t(z) * r * r]) {
                        coords[0].push_back(base + (x + 0.5f) * cell);
                        coords[1].push_back(base + (y + 0.5f) * cell);
                        coords[2].push_back(base + (z + 0.5f) * cell);
                    }
    }
    Vec3 lo(INFINITY), hi(-INFINITY);
    for (int a = 0; a < 3 && !coords[a].empty(); ++a) {
        auto& q = coords[a];
        std::sort(q.begin(), q.end());
        lo[a] = q[size_t(0.01 * double(q.size() - 1))];
        hi[a] = q[size_t(0.99 * double(q.size() - 1))];
    }
    fmt::print("aabb       model space 0.5 +- {} (aabb_scale {})\n", 0.5f * m.aabb_scale, m.aabb_scale);
    if (lo.x <= hi.x) {
        const Mat4 to_world = m.world_to_model.inverse();
        const Vec3 a = to_world.transform_point(lo), b = to_world.transform_point(hi);
        fmt::print("content    per axis, 98% of the occupied cells lie in model {} .. {}, training world {} .. {}\n", vec(lo),
                   vec(hi),
                   vec(vmin(a, b)), vec(vmax(a, b)));
    } else {
        fmt::print("content    no occupied cells\n");
    }
    print_object(m);
    return 0;
}

}  // namespace

int run_info(const InfoArgs& args, const GlobalSettings& /*global*/) {
    std::string ext = std::filesystem::path(args.scene).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return char(std::tolower(ch)); });
    if (ext == ".npt") return print_model_info(args.scene);
    scene::LoadOptions load;
    load.camera_name = args.camera;
    const Scene s = scene::load_scene(args.scene, load);
    fmt::print("file       {}\n", s.source.string());
    print_meshes(s);
    print_materials(s);
    print_lights(s);
    print_camera(s);
    print_volumes(s);
    const auto& r = s.settings;
    fmt::print("render     {}x{}, {} spp, max depth {}, seed {} (command-line options override these)\n",
               r.width, r.height, r.spp, r.max_depth, r.seed);
    return 0;
}

}  // namespace npt::cli
