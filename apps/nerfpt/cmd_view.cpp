#include "cmd_view.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <stdlib.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <optional>
#include <vector>

#include "cmd_render.h"
#include "core/error.h"
#include "core/executable.h"
#include "core/image_io.h"
#include "core/progress.h"
#include "dataset_loading.h"
#include "input_checks.h"
#include "interrupt.h"
#include "nerf/dataset.h"
#include "nerf/eval_images.h"
#include "nerf/model_file.h"
#include "nerf/object_frame.h"
#include "nerf/orbit_camera.h"
#include "backend_option.h"
#include "nerf/render_view.h"

namespace npt::cli {
namespace fs = std::filesystem;

namespace {
constexpr int k_default_orbit_frames = 120;
constexpr int k_default_orbit_side = 800;
constexpr double k_default_orbit_fov = 40.0;  // NeRF-synthetic's camera_angle_x is 0.6911 rad = 39.6 deg
}  // namespace

CLI::App* add_view_command(CLI::App& app, ViewArgs& args) {
    CLI::App* cmd = app.add_subcommand(
        "view", "Render novel views of a trained model: one data-set camera, or an orbit video around it");
    cmd->footer(
        "Without --camera, renders an orbit: --orbit frames on a circle around the centre of the model's\n"
        "cube (with --object: of the object's box), at --elevation degrees above the horizontal plane and\n"
        "--distance world units from the centre, looking at it. Up is world +Z, as in NeRF-synthetic (the\n"
        "world space of the training cameras). The default distance is 1.32 model units (4.0 world units\n"
        "for a model trained on NeRF-synthetic, whose cameras sit at radius 4). The background is white.\n"
        "OUT ending in .mp4 is encoded with ffmpeg (libx264, yuv420p: width and height must be even;\n"
        "ffmpeg must be on PATH); OUT ending in .png writes OUT_0000.png, OUT_0001.png, ... instead.\n"
        "With --camera, OUT must end in .png and gets the one image.\n"
        "Examples: nerfpt view lego.npt -o lego.mp4 --orbit 120 --res 400x400\n"
        "          nerfpt view lego.npt -o r_7.png --camera ../shared/data/nerf_synthetic/lego:7\n"
        "          nerfpt view capture/model.npt -o object.mp4 --object   (the captured object alone)");
    cmd->add_option("MODEL", args.model, "Model file written by 'nerfpt train' (.npt)")->required();
    cmd->add_option("-o,--output", args.output, "Output: .mp4 video or .png image(s); its folder must exist")
        ->required();
    CLI::Option* camera =
        cmd->add_option("--camera", args.camera,
                        "DATA:INDEX: render camera INDEX (from 0) of a transforms.json, or of a folder's "
                        "transforms_{SPLIT}.json (images are loaded too, for their size)");
    cmd->add_option("--split", args.split,
                    "With --camera on a folder: which transforms_{SPLIT}.json (default: test)")
        ->needs(camera);
    cmd->add_option("--orbit", args.orbit,
                    "Frames in the orbit, one full turn (default: 120 when --camera is not given)")
        ->check(CLI::Range(1, 100000))
        ->excludes(camera);
    cmd->add_option("--res", args.res,
                    "Image size WIDTHxHEIGHT (default: the camera's, or 800x800 for an orbit); with --camera "
                    "the intrinsics are scaled to it")
        ->check(CLI::Validator(
            [](std::string& text) {
                int w = 0, h = 0;
                try {
                    parse_resolution(text, &w, &h);
                } catch (const Error& e) {
                    return std::string(e.what());
                }
                return std::string();
            },
            "WxH"));
    cmd->add_option("--fov", args.fov,
                    "Horizontal field of view in degrees, 1..179 (default: the camera's, or 40 for an orbit)")
        ->check(CLI::Range(1.0f, 179.0f));
    cmd->add_option("--elevation", args.elevation,
                    "Orbit: degrees above the horizontal plane through the centre, -89..89 (default: 30)")
        ->check(CLI::Range(-89.0f, 89.0f))
        ->excludes(camera);
    cmd->add_option("--distance", args.distance,
                    "Orbit: distance from the centre in world units (default: 1.32 / the model's "
                    "world-to-model scale, 4.0 for NeRF-synthetic)")
        ->check(CLI::Range(1e-6f, 1e6f))
        ->excludes(camera);
    cmd->add_option("--fps", args.fps, "Video frame rate, 1..240 (default: 30)")
        ->check(CLI::Range(1.0f, 240.0f))
        ->excludes(camera);
    cmd->add_flag("--object", args.object,
                  "Only the captured object: what lies inside the model's object box (the object frame `nerfpt "
                  "capture` stores), cut as a scene's volume with \"placement\": \"object\" cuts it; an orbit "
                  "then circles the box's centre");
    add_backend_option(cmd, args.backend);
    cmd->add_option("--threads", args.threads, "Worker threads, 0 = all hardware threads (default: 0)")
        ->check(CLI::Range(0, 4096));
    return cmd;
}

namespace {

std::string lower_extension(const fs::path& p) {
    std::string ext = p.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

// A fresh folder under the system's temporary folder, removed with everything in it when this goes away
// (also when rendering fails or is interrupted).
class TempFolder {
  public:
    TempFolder() {
        std::string pattern = (fs::temp_directory_path() / "nerfpt-view-XXXXXX").string();
        if (!mkdtemp(pattern.data()))
            throw Error("cannot create a temporary folder in " + fs::temp_directory_path().string());
        m_path = pattern;
    }
    ~TempFolder() {
        std::error_code ec;
        fs::remove_all(m_path, ec);
    }
    TempFolder(const TempFolder&) = delete;
    TempFolder& operator=(const TempFolder&) = delete;
    const fs::path& path() const { return m_path; }

  private:
    fs::path m_path;
};

// Runs ffmpeg without a shell (no quoting problems with odd file names), its output into a log file. The
// child gets an empty signal mask: ours blocks SIGINT for the interrupt watcher, and Ctrl-C must stop ffmpeg.
void run_ffmpeg(const fs::path& ffmpeg, const fs::path& frames, float fps, const fs::path& out) {
    const fs::path log = frames / "ffmpeg.log";
    const std::string rate = fmt::format("{}", fps);
    const std::string input = (frames / "frame_%04d.png").string();
    std::vector<std::string> argv_s = {ffmpeg.string(), "-nostdin", "-loglevel", "error",     "-y",
                                       "-framerate",    rate,       "-i",        input,       "-pix_fmt",
                                       "yuv420p",       "-c:v",     "libx264",   out.string()};
    const int status = run_logged(argv_s, log);
    if (status == 0) return;
    // ffmpeg's last line says what went wrong (an unknown encoder, an odd size, a full disk).
    std::ifstream f(log);
    std::string line, last;
    while (std::getline(f, line))
        if (!line.empty()) last = line;
    const std::string how = status < 128 ? "exit code " + std::to_string(status)
                                          : "signal " + std::to_string(status - 128);
    throw Error("ffmpeg failed writing '" + out.string() + "' (" + how + ")" +
                (last.empty() ? "" : ": " + last));
}

// "DATA:INDEX" split at the last colon, so DATA may contain colons.
std::pair<std::string, size_t> parse_camera_arg(const std::string& text) {
    const size_t colon = text.rfind(':');
    const std::string index = colon == std::string::npos ? "" : text.substr(colon + 1);
    if (colon == std::string::npos || colon == 0 || index.empty() || index.size() > 9 ||
        !std::all_of(index.begin(), index.end(), [](char c) { return c >= '0' && c <= '9'; }))
        throw Error("--camera '" + text +
                    "': expected DATA:INDEX, e.g. data/lego:0 or transforms_test.json:12");
    return {text.substr(0, colon), size_t(std::stoul(index))};
}

nerf::Camera data_camera(const ViewArgs& args, const std::string& data_path, size_t index,
                         std::vector<InputFile>* inputs) {
    const nerf::Dataset data = nerf::load_dataset(data_path, args.split);
    *inputs = dataset_inputs(data, std::move(*inputs));
    if (index >= data.cameras.size())
        throw Error("--camera '" + args.camera + "': index " + std::to_string(index) + " is out of range (" +
                    std::to_string(data.cameras.size()) + " frames)");
    nerf::Camera cam = data.cameras[index];
    if (!args.res.empty()) {
        int w = 0, h = 0;
        parse_resolution(args.res, &w, &h);
        const float sx = float(w) / float(cam.width), sy = float(h) / float(cam.height);
        cam.fx *= sx;
        cam.cx *= sx;
        cam.fy *= sy;
        cam.cy *= sy;
        cam.width = w;
        cam.height = h;
    }
    if (args.fov > 0) cam.fx = cam.fy = nerf::focal_from_fov(cam.width, args.fov);
    return cam;
}

}  // namespace

int run_view(const ViewArgs& args, const GlobalSettings& global, InterruptGuard& interrupts) {
    check_requested_backend(args.backend);
    // Every check that needs no loading first: a typo must fail at once.
    require_file(args.model, "MODEL");
    const fs::path out = args.output;
    const std::string ext = lower_extension(out);
    const bool video = ext == ".mp4";
    if (ext != ".png" && !video) throw Error("--output '" + out.string() + "': must end in .mp4 or .png");
    if (out.stem().empty()) throw Error("--output '" + out.string() + "': needs a file name");
    require_writable_parent(out, "--output");
    std::string data_path;
    size_t camera_index = 0;
    if (!args.camera.empty()) {
        if (video) throw Error("--camera renders one image: --output must end in .png");
        std::tie(data_path, camera_index) = parse_camera_arg(args.camera);
        require_path(data_path, "--camera: DATA");
    }
    int width = k_default_orbit_side, height = k_default_orbit_side;
    if (!args.res.empty()) parse_resolution(args.res, &width, &height);
    fs::path ffmpeg;
    if (video) {
        if (width % 2 || height % 2)
            throw Error("--res " + args.res + ": an .mp4 (yuv420p) needs an even width and height");
        ffmpeg = find_executable("ffmpeg");
        if (ffmpeg.empty())
            throw Error("--output '" + out.string() +
                        "': writing .mp4 needs ffmpeg on PATH (install it, or write .png frames instead)");
    }
    std::optional<tbb::global_control> threads;
    if (args.threads > 0) threads.emplace(tbb::global_control::max_allowed_parallelism, args.threads);

    const nerf::NerfModel model = nerf::load_model(args.model);
    if (args.object && !model.object)
        throw Error(args.model + ": --object: the model has no object frame (made by `nerfpt capture`)");
    std::vector<nerf::Camera> cameras;
    std::vector<InputFile> inputs{{"MODEL", args.model}};
    if (!args.camera.empty()) {
        cameras.push_back(data_camera(args, data_path, camera_index, &inputs));
    } else {
        nerf::OrbitSettings orbit;
        orbit.centre = args.object ? nerf::object_box_centre_world(*model.object) : nerf::model_centre_world(model);
        orbit.distance = args.distance > 0 ? double(args.distance) : nerf::default_orbit_distance(model);
        orbit.elevation_deg = args.elevation;
        orbit.width = width;
        orbit.height = height;
        orbit.fov_deg = args.fov > 0 ? double(args.fov) : k_default_orbit_fov;
        const int frames = args.orbit > 0 ? args.orbit : k_default_orbit_frames;
        for (int k = 0; k < frames; ++k)
            cameras.push_back(nerf::orbit_camera(orbit, 2.0 * std::numbers::pi * k / frames));
        spdlog::info("orbit of {} frames around ({:.3f}, {:.3f}, {:.3f}), distance {:.3f}, elevation {} deg",
                     frames, orbit.centre.x, orbit.centre.y, orbit.centre.z, orbit.distance,
                     orbit.elevation_deg);
    }

    // Frames go to a temporary folder for ffmpeg, or straight beside OUT.
    std::optional<TempFolder> temp;
    if (video) temp.emplace();
    const auto frame_path = [&](size_t k) {
        if (!args.camera.empty()) return out;
        if (video) return temp->path() / fmt::format("frame_{:04}.png", k);
        return out.parent_path() / fmt::format("{}_{:04}.png", out.stem().string(), k);
    };
    refuse_overwriting_inputs(out, "--output", inputs);  // e.g. -o r_7.png beside data set image r_7.png
    for (size_t k = 0; !video && k < cameras.size(); ++k)
        refuse_overwriting_inputs(frame_path(k), "--output", inputs);

    ProgressSettings ps;
    ps.label = "view";
    ps.unit = "rows";
    ps.style = progress_style(stream_is_tty(stderr), global.quiet);
    Progress progress(ps, std::cerr);
    uint64_t total_rows = 0;
    for (const nerf::Camera& c : cameras) total_rows += uint64_t(c.height);
    // Cooperative: an interrupt stops the render at the next rows, so the temporary folder is cleaned up.
    // Resolved once the input is known to be good: the CPU fallback's note never precedes an input error.
    const auto renderer = nerf::make_view_renderer(resolve_backend(args.backend), model);
    spdlog::info("rendering on {}", renderer->device());
    nerf::ViewOptions view_options;  // white background
    view_options.object_only = args.object;
    interrupts.set_cooperative(true);
    const auto t0 = std::chrono::steady_clock::now();
    try {
        uint64_t rows_before = 0;
        for (size_t k = 0; k < cameras.size(); ++k) {
            const Image img =
                renderer->render(cameras[k], view_options, [&](size_t done, size_t) {
                    progress.update(rows_before + done, total_rows);
                    return !interrupts.stop_requested();
                });
            rows_before += uint64_t(cameras[k].height);
            auto no_interrupt = interrupts.hold();
            write_png(frame_path(k), nerf::encoded_to_linear(img));  // render values are sRGB-encoded
        }
        progress.finish();
        if (video) run_ffmpeg(ffmpeg, temp->path(), args.fps, out);
    } catch (const Error&) {
        if (!interrupts.stop_requested()) throw;
    }
    interrupts.set_cooperative(false);
    if (interrupts.stop_requested()) {
        fmt::print(stderr, "nerfpt: interrupted\n");
        return 128 + interrupts.stop_signal();
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!args.camera.empty() || video)
        fmt::print("wrote {}\n", out.string());
    else
        fmt::print("wrote {} .. {}\n", frame_path(0).string(), frame_path(cameras.size() - 1).string());
    fmt::print("rendered {} frame{} of {}x{} in {}\n", cameras.size(), cameras.size() == 1 ? "" : "s",
               cameras[0].width, cameras[0].height, format_seconds(seconds));
    return 0;
}

}  // namespace npt::cli
