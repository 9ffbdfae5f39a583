// Renders the end-to-end test's turntable (tests/e2e/turntable_scene.h) as a video with its true poses, for
// measuring the poses stage outside the test (docs/benchmarks.md, "How fast COLMAP can be"). Usage:
// nerfpt_make_turntable_capture OUT_DIR [--width W] [--height H] [--frames N] [--fov-y DEG] [--spp N]
// [--rich] writes OUT_DIR/turntable.mp4, OUT_DIR/truth.json (frame_NNNNN.png = video frame NNNNN, as curate
// names them) and the rendered frames in OUT_DIR/render/.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <string>

#include "e2e/turntable_scene.h"

int main(int argc, char** argv) {
    const char* usage =
        "usage: nerfpt_make_turntable_capture OUT_DIR [--width W] [--height H] [--frames N] [--fov-y DEG] "
        "[--spp N] [--rich]\n";
    if (argc < 2) {
        std::fputs(usage, stderr);
        return 2;
    }
    npt::test::TurntableSettings st;
    for (int i = 2; i < argc; ++i) {
        const std::string a = argv[i];
        const bool has_value = i + 1 < argc;
        if (a == "--rich") {
            st.rich_texture = true;
        } else if (has_value && a == "--width") {
            st.width = std::atoi(argv[++i]);
        } else if (has_value && a == "--height") {
            st.height = std::atoi(argv[++i]);
        } else if (has_value && a == "--frames") {
            st.frames = std::atoi(argv[++i]);
        } else if (has_value && a == "--fov-y") {
            st.fov_y_deg = std::atof(argv[++i]);
        } else if (has_value && a == "--spp") {
            st.spp = std::atoi(argv[++i]);
        } else {
            std::fprintf(stderr, "nerfpt_make_turntable_capture: unknown or incomplete argument '%s'\n%s",
                         a.c_str(), usage);
            return 2;
        }
    }
    if (st.width < 16 || st.height < 16 || st.width > 8192 || st.height > 8192 || st.frames < 3 ||
        st.frames > 100000 || st.spp < 1 || !(st.fov_y_deg > 1 && st.fov_y_deg < 170)) {
        std::fprintf(stderr,
                     "nerfpt_make_turntable_capture: sizes 16..8192, frames >= 3, spp >= 1, fov 1..170\n");
        return 2;
    }
    try {
        const std::filesystem::path out = argv[1];
        std::filesystem::create_directories(out);
        npt::test::render_turntable_video(st, out / "render", out / "turntable.mp4");
        npt::test::write_true_transforms(st, out / "truth.json");
        std::printf("wrote %d frames of %dx%d%s to %s/turntable.mp4 and truth.json\n", st.frames, st.width,
                    st.height, st.rich_texture ? " (rich texture)" : "", out.c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "nerfpt_make_turntable_capture: %s\n", e.what());
        return 1;
    }
    return 0;
}
