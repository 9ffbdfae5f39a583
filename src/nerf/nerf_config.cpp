// NerfConfig <-> JSON. Every field is read through one small table per group, so that a field's name, type
// and valid range are written once and every error message names the file and "group.field" the same way.
#include "nerf/nerf_config.h"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "core/error.h"
#include "core/json_file.h"
#include "nerf/mlp.h"

namespace npt::nerf {

namespace {

using nlohmann::json;

constexpr int k_sh_inputs = 16;  // SH degree 4 coefficients appended to the density outputs
constexpr double k_inf = std::numeric_limits<double>::infinity();

std::string number_text(double v) {
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof(buf), v);  // shortest form: 0.95, 16777216
    return std::string(buf, r.ptr);
}

// The float as the double with the same shortest decimal form (0.95f -> 0.95), so that the JSON reads as
// written by hand instead of 0.949999988079071; it converts back to the same float.
double float_for_json(float f) {
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof(buf), f);
    *r.ptr = '\0';
    return std::strtod(buf, nullptr);
}

// One JSON group ("encoding", ...): reads its fields and remembers their names, so that anything left over
// is reported as unknown.
class GroupReader {
  public:
    GroupReader(const json& root, const char* group, const std::string& source)
        : m_group(group), m_source(source) {
        auto it = root.find(group);
        if (it == root.end()) return;
        if (!it->is_object())
            throw Error(source + ": field '" + m_group + "' must be an object, got " + it->type_name());
        m_obj = &*it;
    }

    void read_int(const char* key, int& out, int64_t lo, int64_t hi) {
        const json* j = find(key);
        if (!j) return;
        const int64_t v = integer_value(key, *j);
        if (v < lo || v > hi)
            throw range_error(key, "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]",
                              j->is_number_float() ? number_text(j->get<double>()) : j->dump());
        out = int(v);
    }

    void read_u64(const char* key, uint64_t& out) {
        const json* v = find(key);
        if (!v) return;
        if (!v->is_number_unsigned()) throw type_error(key, "a non-negative integer", *v);
        out = v->get<uint64_t>();
    }

    void read_bool(const char* key, bool& out) {
        const json* v = find(key);
        if (!v) return;
        if (!v->is_boolean()) throw type_error(key, "true or false", *v);
        out = v->get<bool>();
    }

    // A finite number in the interval from lo to hi; the open flags exclude an end.
    void read_float(const char* key, float& out, double lo, double hi, bool lo_open, bool hi_open) {
        const json* v = find(key);
        if (!v) return;
        if (!v->is_number()) throw type_error(key, "a number", *v);
        const double d = v->get<double>();
        const bool ok = std::isfinite(d) && std::isfinite(float(d)) && (lo_open ? d > lo : d >= lo) &&
                        (hi_open ? d < hi : d <= hi);
        if (!ok)
            throw range_error(key,
                              std::string("a finite number in ") + (lo_open ? "(" : "[") + number_text(lo) +
                                  ", " + number_text(hi) + (hi_open ? ")" : "]"),
                              number_text(d));
        out = float(d);
    }

    void check_no_unknown() const {
        if (!m_obj) return;
        for (auto it = m_obj->begin(); it != m_obj->end(); ++it) {
            bool known = false;
            for (const auto& k : m_known) known = known || k == it.key();
            if (!known) throw Error(m_source + ": unknown field '" + m_group + "." + it.key() + "'");
        }
    }

    std::string field(const char* key) const { return "'" + m_group + "." + key + "'"; }
    Error range_error(const char* key, const std::string& what, const std::string& got) const {
        return Error(m_source + ": field " + field(key) + " must be " + what + ", got " + got);
    }

  private:
    const json* find(const char* key) {
        m_known.emplace_back(key);
        if (!m_obj) return nullptr;
        auto it = m_obj->find(key);
        return it == m_obj->end() ? nullptr : &*it;
    }

    // Integers beyond int64 saturate, which the caller's range check then reports.
    int64_t integer_value(const char* key, const json& v) const {
        if (v.is_number_unsigned())
            return v.get<uint64_t>() > uint64_t(INT64_MAX) ? INT64_MAX : int64_t(v.get<uint64_t>());
        if (v.is_number_integer()) return v.get<int64_t>();
        // 16.0 is accepted as 16: some tools write every number as a float.
        if (v.is_number_float()) {
            const double d = v.get<double>();
            if (std::isfinite(d) && d == std::floor(d))
                return std::fabs(d) < 9e18 ? int64_t(d) : d > 0 ? INT64_MAX : INT64_MIN;
        }
        throw type_error(key, "an integer", v);
    }

    Error type_error(const char* key, const std::string& what, const json& v) const {
        std::string got = v.is_number() ? number_text(v.get<double>()) : std::string(v.type_name());
        if (v.is_null()) got += " (nlohmann writes NaN and Inf as null)";
        return Error(m_source + ": field " + field(key) + " must be " + what + ", got " + got);
    }

    std::string m_group;
    const std::string& m_source;
    const json* m_obj = nullptr;
    std::vector<std::string> m_known;
};

constexpr int64_t k_int_max = std::numeric_limits<int>::max();
const char* const k_groups[] = {"encoding", "density_mlp", "color_mlp", "occupancy",
                                "march",    "optimizer",   "loss",      "training"};

}  // namespace

NerfConfig cuda_default_config() {
    NerfConfig c;
    c.encoding.grid.levels = 8;
    c.encoding.grid.features_per_level = 4;
    return c;
}

NerfConfig cpu_default_config() {
    NerfConfig c;
    c.encoding.grid.log2_table_size = 17;
    return c;
}

NerfConfig config_from_json(const json& j, const std::string& source, const NerfConfig& base) {
    if (!j.is_object())
        throw Error(source + ": expected a JSON object at the top level, got " + j.type_name());
    for (auto it = j.begin(); it != j.end(); ++it) {
        bool known = false;
        for (const char* g : k_groups) known = known || it.key() == g;
        if (!known) throw Error(source + ": unknown field '" + it.key() + "'");
    }
    NerfConfig c = base;
    {
        GroupReader r(j, "encoding", source);
        HashGridConfig& g = c.encoding.grid;
        r.read_int("levels", g.levels, 1, 32);
        r.read_int("features_per_level", g.features_per_level, 1, 8);
        r.read_int("log2_table_size", g.log2_table_size, 10, 26);
        r.read_int("base_resolution", g.base_resolution, 2, 1 << 16);
        r.read_float("finest_resolution", c.encoding.finest_resolution, 2.0, double(1 << 20), false, false);
        r.read_int("sh_degree", c.encoding.sh_degree, 4, 4);  // the only degree implemented
        r.check_no_unknown();
        // The grid's output is the density MLP's input, which the per-sample forward keeps on the stack.
        if (g.output_dims() > k_max_mlp_width)
            throw Error(source + ": 'encoding.levels' * 'encoding.features_per_level' = " +
                        std::to_string(g.output_dims()) + " exceeds the network width limit of " +
                        std::to_string(k_max_mlp_width));
        if (c.encoding.finest_resolution < float(g.base_resolution))
            throw r.range_error(
                "finest_resolution",
                "at least 'encoding.base_resolution' (" + std::to_string(g.base_resolution) + ")",
                number_text(c.encoding.finest_resolution));
    }
    {
        GroupReader r(j, "density_mlp", source);
        r.read_int("hidden_layers", c.density_mlp.hidden_layers, 1, 16);
        r.read_int("width", c.density_mlp.width, 1, k_max_mlp_width);
        // All outputs plus the SH coefficients form the colour MLP's input.
        r.read_int("outputs", c.density_mlp.outputs, 1, k_max_mlp_width - k_sh_inputs);
        r.check_no_unknown();
    }
    {
        GroupReader r(j, "color_mlp", source);
        r.read_int("hidden_layers", c.color_mlp.hidden_layers, 1, 16);
        r.read_int("width", c.color_mlp.width, 1, k_max_mlp_width);
        r.read_int("outputs", c.color_mlp.outputs, 3, 3);  // RGB
        r.check_no_unknown();
    }
    {
        GroupReader r(j, "occupancy", source);
        OccupancyConfig& o = c.occupancy;
        // 512^3 cells are 512 MiB per cascade already; more is a typo, not a wish.
        r.read_int("resolution", o.resolution, 1, 512);
        r.read_float("decay", o.decay, 0.0, 1.0, true, false);
        r.read_float("threshold", o.threshold, 0.0, k_inf, false, true);
        r.read_int("update_interval", o.update_interval, 1, k_int_max);
        r.read_int("warmup_steps", o.warmup_steps, 0, k_int_max);
        r.check_no_unknown();
    }
    {
        GroupReader r(j, "march", source);
        MarchConfig& m = c.march;
        r.read_int("max_steps", m.max_steps, 1, 1 << 16);
        r.read_float("cone_angle", m.cone_angle, -k_inf, 1.0, true, false);  // < 0: automatic
        r.read_float("min_transmittance", m.min_transmittance, 0.0, 1.0, false, true);
        r.read_int("max_samples_per_ray", m.max_samples_per_ray, 1, 1 << 16);
        r.check_no_unknown();
    }
    {
        GroupReader r(j, "optimizer", source);
        OptimizerConfig& o = c.optimizer;
        r.read_float("learning_rate", o.learning_rate, 0.0, k_inf, true, true);
        // beta = 1 or ema_decay = 1 would make the bias correction divide by zero.
        r.read_float("beta1", o.beta1, 0.0, 1.0, false, true);
        r.read_float("beta2", o.beta2, 0.0, 1.0, false, true);
        r.read_float("epsilon", o.epsilon, 0.0, k_inf, true, true);
        r.read_float("l2_reg", o.l2_reg, 0.0, k_inf, false, true);
        r.read_int("decay_start", o.decay_start, 0, k_int_max);
        r.read_int("decay_interval", o.decay_interval, 1, k_int_max);
        r.read_float("decay_base", o.decay_base, 0.0, 1.0, true, false);
        r.read_float("ema_decay", o.ema_decay, 0.0, 1.0, false, true);
        r.read_bool("sparse_grid", o.sparse_grid);
        r.check_no_unknown();
    }
    {
        GroupReader r(j, "loss", source);
        r.read_float("huber_delta", c.loss.huber_delta, 0.0, k_inf, true, true);
        r.read_float("surface_smoothness", c.loss.surface_smoothness, 0.0, 1e6, false, false);
        r.read_float("smoothness_spacing", c.loss.smoothness_spacing, 1.0, 256.0, false, false);
        r.read_float("smoothness_scale", c.loss.smoothness_scale, 0.0, 1e3, true, false);
        r.check_no_unknown();
    }
    {
        GroupReader r(j, "training", source);
        TrainingConfig& t = c.training;
        r.read_int("batch_samples", t.batch_samples, 256, 1 << 24);
        r.read_int("max_rays_per_batch", t.max_rays_per_batch, 1, 1 << 24);
        r.read_int("cuda_batch_samples", t.cuda_batch_samples, 1 << 12, 1 << 24);
        r.read_u64("seed", t.seed);
        r.read_int("checkpoint_interval", t.checkpoint_interval, 1, k_int_max);
        r.read_bool("random_background", t.random_background);
        r.read_bool("exposure_per_image", t.exposure_per_image);
        r.read_float("exposure_learning_rate", t.exposure_learning_rate, 0.0, 1.0, true, false);
        r.read_float("subject_rays", t.subject_rays, 0.0, 1.0, false, false);
        r.check_no_unknown();
    }
    return c;
}

json config_to_json(const NerfConfig& c) {
    const HashGridConfig& g = c.encoding.grid;
    json j;
    j["encoding"] = {{"levels", g.levels},
                     {"features_per_level", g.features_per_level},
                     {"log2_table_size", g.log2_table_size},
                     {"base_resolution", g.base_resolution},
                     {"finest_resolution", float_for_json(c.encoding.finest_resolution)},
                     {"sh_degree", c.encoding.sh_degree}};
    auto mlp = [](const MlpConfig& m) {
        return json{{"hidden_layers", m.hidden_layers}, {"width", m.width}, {"outputs", m.outputs}};
    };
    j["density_mlp"] = mlp(c.density_mlp);
    j["color_mlp"] = mlp(c.color_mlp);
    const OccupancyConfig& o = c.occupancy;
    j["occupancy"] = {{"resolution", o.resolution},
                      {"decay", float_for_json(o.decay)},
                      {"threshold", float_for_json(o.threshold)},
                      {"update_interval", o.update_interval},
                      {"warmup_steps", o.warmup_steps}};
    const MarchConfig& m = c.march;
    j["march"] = {{"max_steps", m.max_steps},
                  {"cone_angle", float_for_json(m.cone_angle)},
                  {"min_transmittance", float_for_json(m.min_transmittance)},
                  {"max_samples_per_ray", m.max_samples_per_ray}};
    const OptimizerConfig& op = c.optimizer;
    j["optimizer"] = {{"learning_rate", float_for_json(op.learning_rate)},
                      {"beta1", float_for_json(op.beta1)},
                      {"beta2", float_for_json(op.beta2)},
                      {"epsilon", float_for_json(op.epsilon)},
                      {"l2_reg", float_for_json(op.l2_reg)},
                      {"decay_start", op.decay_start},
                      {"decay_interval", op.decay_interval},
                      {"decay_base", float_for_json(op.decay_base)},
                      {"ema_decay", float_for_json(op.ema_decay)},
                      {"sparse_grid", op.sparse_grid}};
    j["loss"] = {{"huber_delta", float_for_json(c.loss.huber_delta)},
                 {"surface_smoothness", float_for_json(c.loss.surface_smoothness)},
                 {"smoothness_spacing", float_for_json(c.loss.smoothness_spacing)},
                 {"smoothness_scale", float_for_json(c.loss.smoothness_scale)}};
    const TrainingConfig& t = c.training;
    j["training"] = {{"batch_samples", t.batch_samples},
                     {"max_rays_per_batch", t.max_rays_per_batch},
                     {"cuda_batch_samples", t.cuda_batch_samples},
                     {"seed", t.seed},
                     {"checkpoint_interval", t.checkpoint_interval},
                     {"random_background", t.random_background},
                     {"exposure_per_image", t.exposure_per_image},
                     {"exposure_learning_rate", float_for_json(t.exposure_learning_rate)},
                     {"subject_rays", float_for_json(t.subject_rays)}};
    return j;
}

NerfConfig load_config(const std::string& path, const NerfConfig& base) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error(path + ": file not found");
    return config_from_json(read_json_file(path), path, base);
}

}  // namespace npt::nerf
