// NerfConfig JSON: round trips (defaults and a config with every group changed), partial files keeping
// defaults, and one message check per kind of bad input (file, syntax, unknown field, type, range).
#include "nerf/nerf_config.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "test_support.h"

namespace npt::nerf {
namespace {

using nlohmann::json;

NerfConfig modified_config() {
    NerfConfig c;
    c.encoding.grid.levels = 8;
    c.encoding.grid.features_per_level = 4;
    c.encoding.grid.log2_table_size = 15;
    c.encoding.grid.base_resolution = 8;
    c.encoding.finest_resolution = 512.5f;
    c.density_mlp = {2, 32, 8};
    c.color_mlp = {3, 128, 3};
    c.occupancy.resolution = 64;
    c.occupancy.decay = 0.9f;
    c.occupancy.threshold = 0.02f;
    c.occupancy.update_interval = 8;
    c.occupancy.warmup_steps = 100;
    c.march.max_steps = 512;
    c.march.cone_angle = 0.004f;
    c.march.min_transmittance = 1e-3f;
    c.march.max_samples_per_ray = 333;
    c.optimizer.learning_rate = 3e-3f;
    c.optimizer.beta1 = 0.8f;
    c.optimizer.beta2 = 0.999f;
    c.optimizer.epsilon = 1e-10f;
    c.optimizer.l2_reg = 0.0f;
    c.optimizer.decay_start = 5000;
    c.optimizer.decay_interval = 2500;
    c.optimizer.decay_base = 0.5f;
    c.optimizer.ema_decay = 0.99f;
    c.loss.huber_delta = 0.1f;
    c.loss.surface_smoothness = 0.05f;
    c.loss.smoothness_spacing = 8.0f;
    c.loss.smoothness_scale = 0.3f;
    c.training.batch_samples = 1 << 18;
    c.training.max_rays_per_batch = 4096;
    c.training.seed = 18446744073709551615ull;
    c.training.checkpoint_interval = 1000;
    c.training.random_background = false;
    return c;
}

TEST(NerfConfig, DefaultsRoundTrip) {
    const json j = config_to_json(NerfConfig{});
    EXPECT_EQ(config_to_json(config_from_json(j, "t.json")), j);
    // Through text too, as in a file; and the floats read as written (0.95, not 0.949999988...).
    EXPECT_EQ(config_to_json(config_from_json(json::parse(j.dump()), "t.json")), j);
    EXPECT_EQ(j.at("occupancy").at("decay").dump(), "0.95");
    EXPECT_EQ(j.at("encoding").size(), 6u);  // per_level_scale is derived, not stored
    EXPECT_FALSE(j.at("encoding").contains("per_level_scale"));
}

TEST(NerfConfig, ModifiedRoundTrip) {
    const NerfConfig c = modified_config();
    const json j = config_to_json(c);
    EXPECT_NE(j, config_to_json(NerfConfig{}));
    const NerfConfig back = config_from_json(json::parse(j.dump(2)), "t.json");
    EXPECT_EQ(config_to_json(back), j);
    EXPECT_EQ(back.encoding.grid.features_per_level, 4);
    EXPECT_EQ(back.encoding.finest_resolution, 512.5f);
    EXPECT_EQ(back.color_mlp.hidden_layers, 3);
    EXPECT_EQ(back.march.cone_angle, 0.004f);
    EXPECT_EQ(back.optimizer.epsilon, 1e-10f);
    EXPECT_EQ(back.optimizer.ema_decay, 0.99f);
    EXPECT_EQ(back.training.seed, 18446744073709551615ull);
    EXPECT_EQ(back.loss.surface_smoothness, 0.05f);
    EXPECT_EQ(back.loss.smoothness_spacing, 8.0f);
    EXPECT_FALSE(back.training.random_background);
}

TEST(NerfConfig, MissingFieldsKeepDefaults) {
    const NerfConfig c =
        config_from_json(json::parse(R"({"encoding": {"levels": 8}, "training": {}})"), "t.json");
    EXPECT_EQ(c.encoding.grid.levels, 8);
    NerfConfig expected;
    expected.encoding.grid.levels = 8;
    EXPECT_EQ(config_to_json(c), config_to_json(expected));
    EXPECT_EQ(config_to_json(config_from_json(json::object(), "t.json")), config_to_json(NerfConfig{}));
    // Integers written as floats are accepted.
    EXPECT_EQ(config_from_json(json::parse(R"({"march": {"max_steps": 256.0}})"), "t.json").march.max_steps,
              256);
}

TEST(NerfConfig, LoadFile) {
    const auto path = test::temp_dir() / "config.json";
    test::write_file(path, R"({"optimizer": {"learning_rate": 0.005}, "loss": {"huber_delta": 0.5}})");
    const NerfConfig c = load_config(path.string());
    EXPECT_EQ(c.optimizer.learning_rate, 0.005f);
    EXPECT_EQ(c.loss.huber_delta, 0.5f);
}

TEST(NerfConfig, MissingFile) {
    const auto path = test::temp_dir() / "nope.json";
    test::expect_error_message([&] { load_config(path.string()); }, {path.string(), "not found"});
}

TEST(NerfConfig, MalformedJson) {
    const auto dir = test::temp_dir();
    for (const char* text : {"{\"encoding\": {\"levels\": 4,}\n}", "", "{\"a\": 1e999}"}) {
        test::write_file(dir / "config.json", text);
        test::expect_error_message([&] { load_config((dir / "config.json").string()); },
                                   {"config.json", *text ? "not valid JSON" : "file is empty"});
    }
}

void expect_bad(const char* text, std::initializer_list<std::string> parts) {
    SCOPED_TRACE(text);
    test::expect_error_message([&] { config_from_json(json::parse(text), "config.json"); }, parts);
}

TEST(NerfConfig, UnknownFields) {
    expect_bad(R"({"encoding": {"levls": 4}})", {"config.json", "unknown field 'encoding.levls'"});
    expect_bad(R"({"encodng": {}})", {"config.json", "unknown field 'encodng'"});
    expect_bad(R"({"encoding": {"per_level_scale": 1.5}})", {"unknown field 'encoding.per_level_scale'"});
}

TEST(NerfConfig, WrongTypes) {
    expect_bad("[1, 2]", {"config.json", "JSON object"});
    expect_bad(R"({"encoding": 4})", {"config.json", "'encoding'", "object"});
    expect_bad(R"({"encoding": {"levels": "16"}})",
               {"config.json", "'encoding.levels'", "integer", "string"});
    expect_bad(R"({"encoding": {"levels": 2.5}})", {"'encoding.levels'", "integer", "2.5"});
    expect_bad(R"({"optimizer": {"learning_rate": null}})", {"'optimizer.learning_rate'", "number", "null"});
    expect_bad(R"({"training": {"random_background": 1}})",
               {"'training.random_background'", "true or false"});
    expect_bad(R"({"training": {"seed": -1}})", {"'training.seed'", "non-negative integer"});
}

TEST(NerfConfig, OutOfRange) {
    expect_bad(R"({"encoding": {"levels": 0}})", {"config.json", "'encoding.levels'", "[1, 32]", "got 0"});
    expect_bad(R"({"encoding": {"levels": 33}})", {"'encoding.levels'", "[1, 32]", "got 33"});
    expect_bad(R"({"encoding": {"levels": 99999999999999999999}})", {"'encoding.levels'", "[1, 32]"});
    expect_bad(R"({"encoding": {"features_per_level": 9}})", {"'encoding.features_per_level'", "[1, 8]"});
    expect_bad(R"({"encoding": {"log2_table_size": 27}})", {"'encoding.log2_table_size'", "[10, 26]"});
    expect_bad(R"({"encoding": {"log2_table_size": 9}})", {"'encoding.log2_table_size'"});
    expect_bad(R"({"encoding": {"sh_degree": 3}})", {"'encoding.sh_degree'"});
    expect_bad(R"({"encoding": {"levels": 32, "features_per_level": 8}})", {"'encoding.levels'", "128"});
    expect_bad(R"({"encoding": {"base_resolution": 64, "finest_resolution": 32}})",
               {"'encoding.finest_resolution'", "base_resolution"});
    expect_bad(R"({"density_mlp": {"width": 129}})", {"'density_mlp.width'", "[1, 128]"});
    expect_bad(R"({"density_mlp": {"outputs": 0}})", {"'density_mlp.outputs'", "[1, 112]"});
    expect_bad(R"({"density_mlp": {"outputs": 113}})", {"'density_mlp.outputs'", "[1, 112]"});
    expect_bad(R"({"density_mlp": {"hidden_layers": 0}})", {"'density_mlp.hidden_layers'"});
    expect_bad(R"({"color_mlp": {"outputs": 4}})", {"'color_mlp.outputs'", "[3, 3]"});
    expect_bad(R"({"occupancy": {"decay": 0}})", {"'occupancy.decay'", "(0, 1]"});
    expect_bad(R"({"occupancy": {"decay": 1.5}})", {"'occupancy.decay'", "(0, 1]", "got 1.5"});
    expect_bad(R"({"occupancy": {"resolution": 100000}})", {"'occupancy.resolution'"});
    expect_bad(R"({"march": {"min_transmittance": 1}})", {"'march.min_transmittance'", "[0, 1)"});
    expect_bad(R"({"optimizer": {"learning_rate": 0}})", {"'optimizer.learning_rate'", "(0, inf)"});
    expect_bad(R"({"optimizer": {"learning_rate": -0.01}})", {"'optimizer.learning_rate'"});
    expect_bad(R"({"optimizer": {"learning_rate": 1e300}})", {"'optimizer.learning_rate'"});  // inf as float
    expect_bad(R"({"optimizer": {"beta2": 1}})", {"'optimizer.beta2'", "[0, 1)"});
    expect_bad(R"({"optimizer": {"decay_interval": 0}})", {"'optimizer.decay_interval'"});
    expect_bad(R"({"optimizer": {"ema_decay": 1}})", {"'optimizer.ema_decay'"});
    expect_bad(R"({"loss": {"huber_delta": 0}})", {"'loss.huber_delta'"});
    expect_bad(R"({"loss": {"surface_smoothness": -1}})", {"'loss.surface_smoothness'"});
    expect_bad(R"({"loss": {"smoothness_spacing": 0.5}})", {"'loss.smoothness_spacing'", "[1, 256]"});
    expect_bad(R"({"loss": {"smoothness_scale": 0}})", {"'loss.smoothness_scale'"});
    expect_bad(R"({"training": {"batch_samples": 255}})", {"'training.batch_samples'", "[256, 16777216]"});
    expect_bad(R"({"training": {"batch_samples": 16777217}})", {"'training.batch_samples'"});
    expect_bad(R"({"training": {"subject_rays": 1.5}})", {"'training.subject_rays'", "[0, 1]", "got 1.5"});
    expect_bad(R"({"training": {"subject_rays": -0.1}})", {"'training.subject_rays'"});
}

}  // namespace
}  // namespace npt::nerf
