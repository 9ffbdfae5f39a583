#include "cmd_serve.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <memory>

#include "cmd_render.h"
#include "core/error.h"
#include "input_checks.h"
#include "nerf/model_file.h"
#include "render/backend/render_backend.h"
#include "serve/capture_report.h"
#include "serve/model_scene.h"
#include "serve/server.h"
#include "serve/viewer.h"

namespace npt::cli {
namespace fs = std::filesystem;

CLI::App* add_serve_command(CLI::App& app, ServeArgs& args) {
    CLI::App* cmd = app.add_subcommand(
        "serve",
        "View a scene, model or capture in the browser: path-traced progressively, placed and cropped, saved back");
    cmd->footer(
        "Prints a URL; open it in a browser (over SSH: ssh -L 7007:127.0.0.1:7007 HOST, then open it here).\n"
        "The page shows the scene path-traced progressively: one pass at 1/PREVIEW of the resolution after each\n"
        "change (camera drag, WASD fly, an edit), then 1-sample passes at full resolution accumulated up to the\n"
        "target spp, with the spp and samples/s. Select a volume to move/rotate/scale it with the gizmo and set\n"
        "its density, emission, crop box and shading; set punctual lights' intensity, spp, bounces, exposure.\n"
        "Save writes the edits into SCENE itself (SCENE.bak keeps the file as it was), so `nerfpt render SCENE`\n"
        "renders what was placed. Render writes a still beside the scene; keyframes saved become\n"
        "SCENE_STEM.shot.json + SCENE_STEM.camera_path.gltf for `nerfpt render ... --frames`.\n"
        "By default only this machine can connect (127.0.0.1); --host 0.0.0.0 (or another address) requires the\n"
        "random token printed in the URL.\n"
        "A capture's folder (what `nerfpt capture VIDEO -o DIR` wrote: capture.json, model.npt) shows its model.npt\n"
        "in the viewer through DIR/model.serve.json (made once; when the capture found the object: upright on\n"
        "y = 0 at its real size, framed by the camera), and a report page (/report.html, linked from the viewer):\n"
        "the stages and their times as report.md has them, PSNR/SSIM per held-out view with eval's truth | render\n"
        "| error images, and turntable.mp4. Only those files of the folder are served.\n"
        "Examples: nerfpt serve scenes/example/scene.gltf\n"
        "          nerfpt serve lego.npt --port 8080 --backend optix\n"
        "          nerfpt serve beer   (the folder of nerfpt capture Beer.mp4 -o beer)");
    cmd->add_option("INPUT", args.input,
                    "A scene (.gltf, .glb, .obj, .json; saving writes .json and .gltf only), a model (.npt: served "
                    "through MODEL.serve.json, made beside it once; a capture's model stands upright on y = 0) or a "
                    "capture's folder (its model and a report page)")
        ->required();
    cmd->add_option("--host", args.host,
                    "Address to listen on (default: 127.0.0.1, this machine only); any other address requires the "
                    "printed token");
    cmd->add_option("--port", args.port, "TCP port, 1..65535, or 0 for any free one (default: 7007)")
        ->check(CLI::Range(0, 65535));
    cmd->add_option("--backend", args.backend,
                    "Renderer: cpu or optix (default: optix where built and a GPU is usable, else cpu)")
        ->check(CLI::IsMember({"cpu", "optix", "auto"}));
    cmd->add_option("--res", args.res, "Full resolution WIDTHxHEIGHT (default: the scene's)");
    cmd->add_option("--spp", args.spp, "Samples per pixel the view refines to, 1..65536 (default: the scene's)")
        ->check(CLI::Range(1, 65536));
    cmd->add_option("--preview", args.preview,
                    "Resolution divisor of the first frame after a change, 1..16 (default: 4 on the CPU, 1 on OptiX)")
        ->check(CLI::Range(1, 16));
    cmd->add_option("--threads", args.threads, "CPU render threads, 0 = all (default: 0)")->check(CLI::Range(0, 4096));
    cmd->add_option("--output-dir", args.output_dir, "Folder of the stills the Render button writes (default: the scene's)");
    return cmd;
}

int run_serve(const ServeArgs& args, const GlobalSettings& global, InterruptGuard& interrupts) {
    (void)global;
    (void)interrupts;  // Ctrl-C ends the server at once: saves are atomic (a temporary renamed over the file)
    require_path(args.input, "INPUT");
    if (args.backend == "optix") render::choose_render_backend(args.backend, nullptr);  // fails before loading
    if (!args.output_dir.empty() && !fs::is_directory(args.output_dir))
        throw Error("--output-dir: '" + args.output_dir + "' is not a folder");
    fs::path scene = args.input;
    std::unique_ptr<serve::CaptureReport> capture;
    if (fs::is_directory(scene)) {
        capture = std::make_unique<serve::CaptureReport>(scene);
        serve::ModelSceneOptions mo;
        mo.object = capture->object_frame();
        if (capture->elevation_deg()) mo.elevation_deg = *capture->elevation_deg();
        if (!fs::exists(serve::model_scene_path(capture->model())))
            mo.environment_file = serve::write_capture_sky(capture->model(), nerf::load_model(capture->model()));
        scene = serve::scene_for_model(capture->model(), mo);
    } else {
        std::string ext = scene.extension().string();
        for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
        if (ext == ".npt") {
            // A capture's model carries its object frame (stood upright like CAPTURE_DIR's), a relightable one
            // its capture environment (the sky). Read only when the scene is made (once; a kept
            // MODEL.serve.json is used as it is).
            serve::ModelSceneOptions mo;
            if (!fs::exists(serve::model_scene_path(scene))) {
                const nerf::NerfModel model = nerf::load_model(scene);
                mo.object = model.object;
                mo.environment_file = serve::write_capture_sky(scene, model);
            }
            scene = serve::scene_for_model(scene, mo);
        }
    }

    serve::ServerOptions so;
    so.routes = capture.get();
    so.host = args.host;
    so.port = uint16_t(args.port);
    if (!serve::is_loopback_host(args.host)) so.token = serve::random_token();
    serve::Server server(so);  // binds first: a port in use fails before the scene loads

    serve::ViewerOptions vo;
    vo.scene = scene;
    std::string note;
    vo.backend = render::choose_render_backend(args.backend, &note);
    if (!note.empty()) spdlog::info("{}", note);
    if (!args.res.empty()) parse_resolution(args.res, &vo.width, &vo.height);
    vo.target_spp = args.spp;
    vo.preview_divisor = args.preview;
    vo.threads = args.threads;
    vo.output_dir = args.output_dir;
    serve::Viewer viewer(vo, server);
    server.attach(&viewer);
    viewer.start();
    if (!so.token.empty())
        spdlog::warn("listening on {}: anyone who can reach it and has the token can view and edit the scene",
                     args.host);
    fmt::print("nerfpt serve: {} ({} backend) at {}\n", scene.string(), vo.backend, server.url());
    if (capture) {
        const std::string url = server.url();
        const size_t q = url.find('?');
        fmt::print("nerfpt serve: the capture's report at {}report.html{}\n", url.substr(0, q),
                   q == std::string::npos ? "" : url.substr(q));
    }
    std::fflush(stdout);
    server.run();
    viewer.stop();
    return 0;
}

}  // namespace npt::cli
