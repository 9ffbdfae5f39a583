#include "media/volume_set.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/json_file.h"
#include "nerf/model_file.h"

namespace npt::media {

namespace {

float number_field(const nlohmann::json& v, const char* key, float fallback, const std::string& where) {
    if (!v.contains(key)) return fallback;
    const auto& f = v[key];
    if (!f.is_number()) throw Error(where + ": extras.volume." + key + ": expected a number");
    double d = f.get<double>();
    if (!std::isfinite(d) || d < 0.0)
        throw Error(where + ": extras.volume." + key + ": must be finite and >= 0");
    return float(d);
}

}  // namespace

VolumeDesc parse_volume_desc(const std::string& extras_json, const std::string& where) {
    const char* expected =
        " (expected extras {\"volume\": {\"file\": \"...\", \"density_scale\": 1, \"emission_scale\": 1}})";
    if (extras_json.empty()) throw Error(where + ": the `volume` cube has no extras" + expected);
    const nlohmann::json j = parse_json_text(extras_json, where + ": extras");
    if (!j.is_object() || !j.contains("volume") || !j["volume"].is_object())
        throw Error(where + ": extras has no `volume` object" + expected);
    const auto& v = j["volume"];
    VolumeDesc d;
    if (!v.contains("file") || !v["file"].is_string() || v["file"].get<std::string>().empty())
        throw Error(where + ": extras.volume.file: expected the path of a grid file or a nerfpt model (.npt)");
    d.file = v["file"].get<std::string>();
    d.density_scale = number_field(v, "density_scale", 1.0f, where);
    d.emission_scale = number_field(v, "emission_scale", 1.0f, where);
    d.step_voxels = number_field(v, "step_voxels", 0.25f, where);
    if (d.step_voxels < 0.01f || d.step_voxels > 4.0f)
        throw Error(where + ": extras.volume.step_voxels: must lie in [0.01, 4]");
    if (v.contains("crop")) {
        const auto& c = v["crop"];
        auto corner = [&](const char* key, Vec3* out) {
            if (!c.is_object() || !c.contains(key) || !c[key].is_array() || c[key].size() != 3)
                throw Error(where + ": extras.volume.crop." + key + ": expected 3 numbers (model space)");
            for (int a = 0; a < 3; ++a) {
                if (!c[key][a].is_number() || !std::isfinite(c[key][a].get<double>()))
                    throw Error(where + ": extras.volume.crop." + key + ": expected 3 finite numbers");
                (*out)[a] = c[key][a].get<float>();
            }
        };
        corner("min", &d.crop.min);
        corner("max", &d.crop.max);
        for (int a = 0; a < 3; ++a)
            if (!(d.crop.max[a] > d.crop.min[a]))
                throw Error(where + ": extras.volume.crop: max must exceed min on every axis");
        d.has_crop = true;
    }
    if (v.contains("shading")) {
        const auto& sh = v["shading"];
        const std::string value = sh.is_string() ? sh.get<std::string>() : "";
        if (value == "relit")
            d.shading = VolumeShading::Relit;
        else if (value == "emissive")
            d.shading = VolumeShading::Emissive;
        else
            throw Error(where + ": extras.volume.shading: expected \"relit\" or \"emissive\"");
    }
    if (v.contains("placement")) {
        const auto& pl = v["placement"];
        const std::string value = pl.is_string() ? pl.get<std::string>() : "";
        if (value == "object")
            d.placement = VolumePlacement::Object;
        else if (value == "box")
            d.placement = VolumePlacement::Box;
        else
            throw Error(where + ": extras.volume.placement: expected \"object\" or \"box\"");
    }
    if (v.contains("casts_shadows")) {
        if (!v["casts_shadows"].is_boolean())
            throw Error(where + ": extras.volume.casts_shadows: expected true or false");
        d.casts_shadows = v["casts_shadows"].get<bool>();
    }
    return d;
}

bool volume_is_relit(const VolumeDesc& desc, bool relightable, const std::string& where) {
    if (desc.shading == VolumeShading::Relit && !relightable)
        throw Error(where + ": extras.volume.shading: \"relit\" needs a relightable model, and " + desc.file +
                    " is not one (train it with `nerfpt train --relightable`, or use \"emissive\")");
    return desc.shading == VolumeShading::Relit || (desc.shading == VolumeShading::Auto && relightable);
}

void fill_nerf_volume(const nerf::NerfModel& m, const VolumeDesc& desc, Vec3 local_min, Vec3 local_max,
                      const std::string& where, VolumeView& v) {
    v.kind = VolumeKind::Nerf;
    v.nerf.march = m.march_params();
    nerf::CropBox box{v.nerf.march.aabb_min, v.nerf.march.aabb_max};  // the model's box
    if (desc.placement == VolumePlacement::Object && !m.object)
        throw Error(where + ": extras.volume.placement: \"object\" needs a model that carries its object frame "
                    "(made by `nerfpt capture`), and " + desc.file + " does not");
    if (desc.placement == VolumePlacement::Object && desc.has_crop)
        throw Error(where + ": extras.volume.crop: a crop is for \"placement\": \"box\" (the object frame brings its "
                    "own box)");
    const bool object = m.object && !desc.has_crop && desc.placement != VolumePlacement::Box;
    v.local_min = local_min;
    v.local_max = local_max;
    if (object) {
        const nerf::CropBox obox = nerf::object_model_box(*m.object, m.world_to_model);
        box.min = vmax(box.min, obox.min);
        box.max = vmin(box.max, obox.max);
        if (!(box.max.x > box.min.x && box.max.y > box.min.y && box.max.z > box.min.z))
            throw Error(where + ": " + desc.file + ": the object's box lies outside the model's box");
        nerf::object_local_box(*m.object, &v.local_min, &v.local_max);
    } else if (desc.has_crop) {
        box.min = vmax(box.min, desc.crop.min);
        box.max = vmin(box.max, desc.crop.max);
        if (!(box.max.x > box.min.x && box.max.y > box.min.y && box.max.z > box.min.z))
            throw Error(where + ": extras.volume.crop does not overlap the model's box (0.5 +- " +
                        std::to_string(0.5f * m.aabb_scale) + " in model space)");
    }
    v.nerf.field = m.field();
    v.nerf.occupancy = m.occupancy.view();
    v.nerf.march.aabb_min = box.min;
    v.nerf.march.aabb_max = box.max;
    v.nerf.local_to_model = object ? nerf::object_local_to_model(*m.object, m.world_to_model)
                                   : nerf::local_to_model(local_min, local_max, box);
    v.nerf.relit = volume_is_relit(desc, m.relightable(), where);
    v.nerf.intrinsic = v.nerf.relit ? m.intrinsic() : nerf::IntrinsicFieldView{};
}

namespace {
// instant-ngp sigma is per unit of its unit cube, taken to span the cube's longest world side (1 when flat).
float longest_world_side(const scene::VolumeInstance& inst) {
    const Vec3 size = inst.local_max - inst.local_min;
    float longest = 0.0f;
    for (int a = 0; a < 3; ++a) {
        Vec3 axis(0.0f);
        axis[a] = size[a];
        longest = std::max(longest, length(inst.local_to_world.transform_vector(axis)));
    }
    return longest > 0.0f ? longest : 1.0f;
}
}  // namespace

void VolumeSet::set_placement(size_t i, const scene::VolumeInstance& inst) {
    m_views[i].world_to_local = affine_from(inst.local_to_world.inverse());
    m_views[i].density_scale = m_density_scale[i] / (m_per_longest_side[i] ? longest_world_side(inst) : 1.0f);
}

VolumeSet::VolumeSet(const scene::Scene& scene) {
    m_owned.reserve(scene.volumes.size());
    for (const auto& inst : scene.volumes) {
        const std::filesystem::path& declared = inst.declared_in.empty() ? scene.source : inst.declared_in;
        std::string where = declared.string() + ": node '" + inst.name + "'";
        VolumeDesc desc = parse_volume_desc(inst.extras_json, where);
        std::filesystem::path file = desc.file;
        if (file.is_relative()) file = declared.parent_path() / file;
        std::string ext = file.extension().string();
        Mat4 world_to_local = inst.local_to_world.inverse();
        VolumeView v;
        v.world_to_local = affine_from(world_to_local);
        v.local_min = inst.local_min;
        v.local_max = inst.local_max;
        v.density_scale = desc.density_scale;
        v.emission_scale = desc.emission_scale;
        v.step_voxels = desc.step_voxels;
        v.casts_shadows = desc.casts_shadows;
        if (ext == ".npt") {
            Owned owned;
            try {
                owned.model = std::make_unique<nerf::NerfModel>(nerf::load_model(file));
            } catch (const Error& e) {
                throw Error(where + ": " + e.what());
            }
            owned.model->training.reset();  // rendering needs the averaged parameters only
            fill_nerf_volume(*owned.model, desc, inst.local_min, inst.local_max, where, v);
            spdlog::debug("{}: NeRF model {} ({} parameters), queried directly, shading {}", where, file.string(),
                          owned.model->params.size(), v.nerf.relit ? "relit" : "emissive");
            m_owned.push_back(std::move(owned));
            m_density_scale.push_back(desc.density_scale);
            m_per_longest_side.push_back(0);
            m_views.push_back(v);
            continue;
        }

        if (desc.shading == VolumeShading::Relit)
            throw Error(where + ": extras.volume.shading: \"relit\" is for NeRF models (.npt) only; " + desc.file +
                        " is a grid");
        GridLoadOptions opt;
        opt.local_min = inst.local_min;
        opt.local_max = inst.local_max;
        Owned owned;
        owned.grid = load_volume_grid(file, opt);
        owned.majorant = build_majorant(owned.grid, &owned.mx, &owned.my, &owned.mz);
        m_owned.push_back(std::move(owned));

        if (ext == ".bin") v.density_scale /= longest_world_side(inst);
        m_density_scale.push_back(desc.density_scale);
        m_per_longest_side.push_back(ext == ".bin");
        m_views.push_back(v);
        spdlog::debug("{}: volume grid {}x{}x{} from {}", where, m_owned.back().grid.nx, m_owned.back().grid.ny,
                      m_owned.back().grid.nz, file.string());
    }
    // Views point into m_owned, which no longer moves.
    for (size_t i = 0; i < m_views.size(); ++i) {
        if (m_views[i].kind != VolumeKind::Grid) continue;  // a model's vectors did not move with it
        m_views[i].grid = m_owned[i].grid.view();
        m_views[i].majorant =
            MajorantView{m_owned[i].mx, m_owned[i].my, m_owned[i].mz, m_owned[i].majorant.data()};
    }
}

}  // namespace npt::media
