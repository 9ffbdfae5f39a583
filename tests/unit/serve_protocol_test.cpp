// nerfpt serve's message parser (serve/protocol.h): well-formed messages, and every kind of bad one refused with
// a one-line error naming the field.
#include <gtest/gtest.h>

#include <string>

#include "serve/protocol.h"
#include "test_support.h"

namespace npt::serve {
namespace {

TEST(ServeProtocol, ParsesACameraMessage) {
    const ClientMessage m = parse_client_message(
        R"({"type": "camera", "position": [1, 2, 3], "forward": [0, 0, -2], "up": [0, 1, 0], "fov_deg": 50})");
    ASSERT_TRUE(std::holds_alternative<CameraMsg>(m));
    const CameraMsg& c = std::get<CameraMsg>(m);
    EXPECT_EQ(c.position[2], 3.0);
    EXPECT_EQ(c.forward[2], -2.0);
    EXPECT_EQ(c.fov_deg, 50.0);
}

TEST(ServeProtocol, ParsesVolumeEditsAndNormalisesTheRotation) {
    const ClientMessage m = parse_client_message(
        R"({"type": "volume", "index": 0, "translation": [1, 0, 0], "rotation": [0, 0, 0, 2], "scale": [1, 2, 3],
            "density_scale": 2, "crop": {"min": [0, 0, 0], "max": [1, 1, 1]}, "shading": "emissive"})");
    const VolumeMsg& v = std::get<VolumeMsg>(m);
    EXPECT_EQ((*v.rotation)[3], 1.0);
    EXPECT_EQ(*v.density_scale, 2.0);
    EXPECT_TRUE(v.crop.has_value());
    EXPECT_EQ(*v.shading, "emissive");
    const VolumeMsg clear = std::get<VolumeMsg>(parse_client_message(R"({"type": "volume", "index": 1, "crop": null})"));
    EXPECT_TRUE(clear.crop_clear);
}

TEST(ServeProtocol, ParsesTheOtherTypes) {
    EXPECT_TRUE(std::holds_alternative<SaveMsg>(parse_client_message(R"({"type": "save"})")));
    EXPECT_EQ(std::get<SettingsMsg>(parse_client_message(R"({"type": "settings", "spp": 8, "exposure": -1.5})")).spp, 8);
    EXPECT_EQ(*std::get<SettingsMsg>(parse_client_message(R"({"type": "settings", "view": "normal"})")).view, "normal");
    EXPECT_EQ(std::get<RenderStillMsg>(parse_client_message(R"({"type": "render", "spp": 3})")).spp, 3);
    EXPECT_EQ(std::get<LightMsg>(parse_client_message(R"({"type": "light", "index": 2, "intensity_scale": 0.5})")).index, 2);
    EXPECT_EQ(std::get<UseCameraMsg>(parse_client_message(R"({"type": "use_camera", "index": 1})")).index, 1);
    EXPECT_TRUE(std::holds_alternative<KeyframeAddMsg>(parse_client_message(R"({"type": "keyframe_add"})")));
    EXPECT_EQ(std::get<KeyframesSaveMsg>(parse_client_message(R"({"type": "keyframes_save", "seconds_per_key": 2})"))
                  .seconds_per_key,
              2.0);
}

TEST(ServeProtocol, RefusesBadMessagesWithOneLineNamingTheField) {
    using test::expect_error_message;
    const auto bad = [](const std::string& text, std::initializer_list<std::string> parts) {
        expect_error_message([&] { parse_client_message(text); }, parts);
    };
    bad("", {"message", "not valid JSON"});
    bad("{", {"message", "not valid JSON"});
    bad("[1, 2]", {"message", "JSON object"});
    bad(R"({"kind": "camera"})", {"message.type"});
    bad(R"({"type": 3})", {"message.type"});
    bad(R"({"type": "explode"})", {"unknown type 'explode'"});
    bad(R"({"type": "camera", "position": [0, 0], "forward": [0, 0, -1]})", {"camera.position", "3 numbers"});
    bad(R"({"type": "camera", "position": [0, 0, "x"], "forward": [0, 0, -1]})", {"camera.position[2]"});
    bad(R"({"type": "camera", "position": [0, 0, 1e300], "forward": [0, 0, -1]})", {"camera.position[2]"});
    bad(R"({"type": "camera", "position": [0, 0, 0], "forward": [0, 0, 0]})", {"camera.forward", "zero"});
    bad(R"({"type": "camera", "position": [0, 0, 0], "forward": [0, 1, 0], "up": [0, 2, 0]})", {"camera.up", "parallel"});
    bad(R"({"type": "camera", "position": [0, 0, 0], "forward": [0, 0, -1], "fov_deg": 0})", {"camera.fov_deg"});
    bad(R"({"type": "camera", "position": [0, 0, 0], "forward": [0, 0, -1], "zoom": 2})", {"camera.zoom", "unknown field"});
    bad(R"({"type": "volume"})", {"volume.index", "missing"});
    bad(R"({"type": "volume", "index": -1})", {"volume.index"});
    bad(R"({"type": "volume", "index": 1.5})", {"volume.index", "whole number"});
    bad(R"({"type": "volume", "index": 18446744073709551615})", {"volume.index"});
    bad(R"({"type": "volume", "index": 0, "rotation": [0, 0, 0, 0]})", {"volume.rotation", "zero"});
    bad(R"({"type": "volume", "index": 0, "scale": [1, 0, 1]})", {"volume.scale"});
    bad(R"({"type": "volume", "index": 0, "density_scale": -1})", {"volume.density_scale"});
    bad(R"({"type": "volume", "index": 0, "crop": {"min": [0, 0, 0], "max": [1, 0, 1]}})", {"volume.crop", "exceed"});
    bad(R"({"type": "volume", "index": 0, "crop": 3})", {"volume.crop"});
    bad(R"({"type": "volume", "index": 0, "shading": "shiny"})", {"volume.shading"});
    bad(R"({"type": "settings", "spp": 0})", {"settings.spp"});
    bad(R"({"type": "settings", "spp": 100000000})", {"settings.spp"});
    bad(R"({"type": "settings", "max_depth": 1000})", {"settings.max_depth"});
    bad(R"({"type": "settings", "exposure": 99})", {"settings.exposure"});
    bad(R"({"type": "settings", "preview_divisor": 0})", {"settings.preview_divisor"});
    bad(R"({"type": "settings", "view": "x-ray"})", {"settings.view"});
    bad(R"({"type": "settings", "view": 3})", {"settings.view"});
    bad(R"({"type": "light", "index": 0})", {"light"});
    bad(R"({"type": "save", "path": "/etc/passwd"})", {"save.path", "unknown field"});
    bad(R"({"type": "keyframes_save", "seconds_per_key": 0})", {"keyframes_save.seconds_per_key"});
}

TEST(ServeProtocol, RefusesOversizedAndDeeplyNestedMessages) {
    using test::expect_error_message;
    const std::string big = R"({"type": "save", "x": ")" + std::string(k_max_message_bytes, 'a') + "\"}";
    expect_error_message([&] { parse_client_message(big); }, {"message", "bytes", "allowed"});
    const std::string deep = std::string(10000, '[') + std::string(10000, ']');
    expect_error_message([&] { parse_client_message(deep); }, {"message", "nested"});
}

}  // namespace
}  // namespace npt::serve
