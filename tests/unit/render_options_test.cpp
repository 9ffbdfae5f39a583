// resolve_options: scene defaults fill what the command line left out; nonsense is refused with a message
// that names the option, before anything is allocated or rendered.
#include <gtest/gtest.h>

#include "core/error.h"
#include "render/renderer.h"
#include "test_support.h"

namespace npt::render {
namespace {

void expect_options_error(const RenderOptions& o, const std::string& needle) {
    scene::Scene s;
    test::expect_error_message([&] { resolve_options(s, o); }, {needle});
}

TEST(RenderOptions, SceneSettingsFillUnsetOptions) {
    scene::Scene s;
    s.settings.width = 320;
    s.settings.height = 240;
    s.settings.spp = 16;
    s.settings.max_depth = 5;
    RenderOptions r = resolve_options(s, {});
    EXPECT_EQ(r.width, 320);
    EXPECT_EQ(r.height, 240);
    EXPECT_EQ(r.spp, 16);
    EXPECT_EQ(r.max_depth, 5);
    RenderOptions o;
    o.width = 64;
    o.height = 32;
    o.spp = 2;
    o.max_depth = 0;
    r = resolve_options(s, o);
    EXPECT_EQ(r.width, 64);
    EXPECT_EQ(r.spp, 2);
    EXPECT_EQ(r.max_depth, 0);
}

TEST(RenderOptions, RejectsZeroAbsurdAndUnknown) {
    RenderOptions o;
    o.width = 1;
    o.height = 0;
    expect_options_error(o, "--res");
    o.width = k_max_resolution + 1;
    o.height = 10;
    expect_options_error(o, "--res");
    o.width = k_max_resolution;
    o.height = k_max_resolution;  // each side allowed, but 1.07 G pixels is not
    expect_options_error(o, "pixels");
    o = {};
    o.width = o.height = 8;
    o.spp = k_max_spp + 1;
    expect_options_error(o, "--spp");
    o.spp = -3;
    expect_options_error(o, "--spp");
    o.spp = 1;
    o.max_depth = k_max_depth + 1;
    expect_options_error(o, "--max-depth");
    o.max_depth = 4;
    o.threads = -1;
    expect_options_error(o, "--threads");
    o.threads = 0;
    o.backend = "gpu";
    expect_options_error(o, "unknown backend 'gpu' (available: cpu, optix)");
    o.backend = "vulkan";
    expect_options_error(o, "unknown backend");
}

}  // namespace
}  // namespace npt::render
