#include "render_sequence.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iostream>

#include "core/error.h"
#include "core/image_io.h"
#include "core/progress.h"
#include "dist/frames.h"
#include "frame_writer.h"
#include "image_pool.h"
#include "interrupt.h"
#include "render/backend/render_backend.h"
#include "render/scene_data.h"
#include "render_outputs.h"
#include "scene/animation.h"
#include "scene/scene.h"

namespace npt::cli {
namespace fs = std::filesystem;

namespace {

// The frame's header: fps, the camera (OpenEXR's worldToCamera: row vectors, x right, y up, z the viewing
// direction) and nerfpt's own frame number, time, vertical field of view and seed.
ExrMetadata frame_metadata(const render::CameraView& cam, int frame, double time, double fps, uint64_t seed) {
    ExrMetadata m;
    m.fps = fps;
    m.has_camera = true;
    const Vec3 axes[3] = {cam.right, cam.up, cam.forward};
    for (int i = 0; i < 3; ++i) {
        m.world_to_camera[0][i] = axes[i].x;
        m.world_to_camera[1][i] = axes[i].y;
        m.world_to_camera[2][i] = axes[i].z;
        m.world_to_camera[3][i] = -dot(axes[i], cam.position);
    }
    m.world_to_camera[3][3] = 1.0f;
    m.ints.push_back({"nerfpt.frame", frame});
    m.floats.push_back({"nerfpt.time", float(time)});
    m.floats.push_back({"nerfpt.yfov", float(2.0 * std::atan(double(cam.tan_half_fov_y)))});
    m.strings.push_back({"nerfpt.seed", std::to_string(seed)});
    return m;
}

}  // namespace

int run_render_sequence(const RenderArgs& args, const GlobalSettings& global, InterruptGuard& interrupts,
                        const FrameSharing& sharing) {
    if (args.denoise) throw Error("--denoise: not available with --frames yet (render the frames as stills)");
    if (args.backend == "optix") render::choose_render_backend(args.backend, nullptr);  // fails before loading
    const fs::path pattern = args.output;
    if (!dist::has_frame_pattern(pattern))
        throw Error("--output '" + pattern.string() + "': a sequence needs #### in the file name (shot.####.exr)");
    const dist::FrameRange range = dist::parse_frame_range(args.frames);
    const std::vector<int> shot = range.frames();
    const dist::TaskSlot task = dist::resolve_task(args.task_index >= 0 ? std::optional<int>(args.task_index) : std::nullopt,
                                                   args.task_count >= 0 ? std::optional<int>(args.task_count) : std::nullopt,
                                                   [](const char* name) -> const char* { return std::getenv(name); });
    const std::vector<int> frames = dist::task_frames(shot, task.index, task.count);
    check_output(dist::frame_path(pattern, range.first));
    const uint32_t aov_mask = args.aovs.empty() ? 0u : render::parse_aov_list(args.aovs);

    render::RenderOptions options = render_options_from_args(args, aov_mask);

    scene::Scene scene = scene::load_scene(args.scene, scene_load_options(args));
    const std::vector<InputFile> inputs = scene_inputs(scene);
    for (int f : frames) {
        fs::path exr = dist::frame_path(pattern, f), png = exr;
        png.replace_extension(".png");
        refuse_overwriting_inputs(exr, "--output", inputs);
        refuse_overwriting_inputs(png, "--output", inputs);
        if (args.aov_files)
            for (const AovFile& a : aov_file_paths(exr, aov_mask)) refuse_overwriting_inputs(a.path, "--aov-files", inputs);
    }
    const uint64_t seed = args.seed_given ? args.seed : scene.settings.seed;
    options.seed = seed;
    const double fps = args.fps > 0 ? args.fps : scene.settings.fps;
    std::string note;
    options.backend = render::choose_render_backend(args.backend, &note);
    if (!note.empty()) spdlog::info("{}", note);
    const render::RenderOptions resolved = render::resolve_options(scene, options);
    if (!scene.animation)
        spdlog::warn("{}: the scene has no animation: every frame is the same view (with its own noise)", args.scene);

    // What is left: frames whose EXR is not already whole (the EXR is written last, so a whole EXR means a
    // finished frame).
    std::vector<int> todo;
    for (int f : frames)
        if (args.overwrite || !exr_reads_back_whole(dist::frame_path(pattern, f), resolved.width, resolved.height))
            todo.push_back(f);
    const std::string task_text =
        task.count > 1 ? fmt::format("task {} of {}: ", task.index, task.count) : std::string();
    const size_t already = frames.size() - todo.size();
    spdlog::info("{}{} of {} frames to render ({} already done), {}x{}, {} spp, {} fps, backend {}", task_text,
                 todo.size(), frames.size(), already, resolved.width, resolved.height, resolved.spp, fps,
                 resolved.backend);
    const bool all_done = todo.empty();
    if (sharing.share) todo = sharing.share(todo);  // this rank's part of rank 0's list
    if (scene.animation)
        spdlog::info("animation '{}': {:.3f} s to {:.3f} s (frames {:.1f} to {:.1f})", scene.animation->animation.name,
                     scene.animation->animation.start, scene.animation->animation.end,
                     scene.animation->animation.start * fps, scene.animation->animation.end * fps);
    if (all_done) {
        if (sharing.leader)
            fmt::print("nothing to render: {} frames already written (--overwrite renders them again)\n", frames.size());
        return 0;
    }
    if (todo.empty()) return 0;  // more ranks than frames left

    // Prepared once, at the file's rest pose, whichever frame comes first: every process builds the same
    // structures and poses them to its frame, so a frame is the same image whichever task renders it.
    const auto renderer = render::prepare_renderer(scene, resolved);
    ProgressSettings ps;
    ps.style = progress_style(stream_is_tty(stderr), global.quiet);
    const auto t_shot = std::chrono::steady_clock::now();
    const auto since = [](std::chrono::steady_clock::time_point t) {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    };
    double pose_s = 0.0, render_s = 0.0;  // the shot's time in posing + updating, and in rendering
    size_t done = 0;
    ImagePool images;  // declared before the writer: its pending writes hold images until it is gone
    // Frames are written by their own threads while the next ones render; each reports here, in order.
    FrameWriter writer(args.writers > 0 ? args.writers : FrameWriter::default_in_flight(), [&](int f, double write_s) {
        ++done;
        const fs::path exr = dist::frame_path(pattern, f);
        const double shot_s = since(t_shot);
        const double left_s = shot_s / double(done) * double(todo.size() - done);
        if (sharing.share)  // this rank's frames
            fmt::print("wrote {} (frame {}, {:.3f} s), its files in {}; {}{}{} of {} frames, {} left\n", exr.string(),
                       f, scene::frame_time(f, fps), format_seconds(write_s), task_text, sharing.rank_text, done,
                       todo.size(), format_seconds(left_s));
        else
            fmt::print("wrote {} (frame {}, {:.3f} s), its files in {}; {}{} of {} frames, {} left\n", exr.string(), f,
                       scene::frame_time(f, fps), format_seconds(write_s), task_text, done + already, frames.size(),
                       format_seconds(left_s));
        std::fflush(stdout);
    });
    for (int f : todo) {
        const double time = scene::frame_time(f, fps);
        const auto t_pose = std::chrono::steady_clock::now();
        renderer->update(scene::pose_scene(scene, time));
        pose_s += since(t_pose);
        render::RenderOptions frame_options = resolved;
        frame_options.seed = dist::frame_seed(seed, f);
        Progress progress(ps, std::cerr);
        const auto t0 = std::chrono::steady_clock::now();
        auto aovs = std::make_shared<render::AovImages>();
        std::shared_ptr<ImagePool::Slot> slot = images.take();
        renderer->render_into(
            frame_options, slot->image, [&progress](uint64_t d, uint64_t total) { progress.update(d, total); },
            aovs.get());
        if (!slot->pin) slot->pin = renderer->pin(slot->image);  // sized now; the next frames download faster
        std::shared_ptr<const Image> image(slot, &slot->image);
        progress.finish();
        render_s += since(t0);
        const ExrMetadata meta =
            frame_metadata(render::make_camera_view(scene, resolved.width, resolved.height), f, time, fps, frame_options.seed);
        const fs::path exr = dist::frame_path(pattern, f);
        writer.submit(f, [&interrupts, &args, aov_mask, exr, image, aovs, meta] {
            fs::path png = exr;
            png.replace_extension(".png");
            auto no_interrupt = interrupts.hold();  // whole files only: an interrupt waits for this frame's writes
            write_render_png(png, *image, args.exposure);
            if (args.aov_files)
                for (const AovFile& a : aov_file_paths(exr, aov_mask)) write_aov_file(a, *aovs);
            write_exr_layers(exr, *image, aov_layers(*aovs, aov_mask), &meta);  // last: it marks the frame done
        });
    }
    writer.finish_all();
    const double shot_s = since(t_shot);
    fmt::print("{}rendered {} frames in {}\n", sharing.rank_text, done, format_seconds(shot_s));
    // Where a frame's time goes (the shot benchmark, docs/benchmarks.md): rendering, posing the scene, and what
    // the render loop waited for its {} writer threads (writing beyond what overlapped the rendering).
    spdlog::info("{}per frame: {:.2f} ms rendering, {:.2f} ms posing and updating, {:.2f} ms waiting for the "
                 "files ({} writer threads), {:.2f} ms in all",
                 sharing.rank_text, 1e3 * render_s / double(done), 1e3 * pose_s / double(done),
                 1e3 * writer.waited_seconds() / double(done), writer.max_in_flight(), 1e3 * shot_s / double(done));
    return 0;
}

}  // namespace npt::cli
