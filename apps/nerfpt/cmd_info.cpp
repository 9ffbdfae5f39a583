#include "cmd_info.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

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
    }
}

}  // namespace

CLI::App* add_info_command(CLI::App& app, InfoArgs& args) {
    CLI::App* cmd =
        app.add_subcommand("info", "Print what a scene holds: meshes, materials, lights, camera, volumes");
    cmd->footer("Example: nerfpt info scenes/example/scene.gltf");
    cmd->add_option("SCENE", args.scene, "Scene file: .gltf, .glb, .obj or .json (docs/formats.md)")
        ->required();
    cmd->add_option("--camera", args.camera,
                    "Camera to describe, by glTF node or camera name (default: the first)");
    return cmd;
}

int run_info(const InfoArgs& args, const GlobalSettings& /*global*/) {
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
