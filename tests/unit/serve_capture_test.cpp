// nerfpt serve CAPTURE_DIR (serve/capture_report.h, serve/model_scene.h): a small fake capture folder (an
// untrained 2-level model with an object frame, capture.json, report.md, eval/ with metrics and PNGs, a fake
// turntable.mp4) read into the report's JSON; only its own files served, traversal attempts and symbolic
// links refused; byte ranges; one-line errors for folders that are not (finished) captures; and its model
// standing in the view of the scene made for it.
#include <gtest/gtest.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <thread>

#include "core/image_io.h"
#include "lights/environment.h"
#include "nerf/relight/relight_env.h"
#include "nerf/model_file.h"
#include "nerf/nerf_model.h"
#include "nerf/object_frame.h"
#include "serve/capture_report.h"
#include "serve/model_scene.h"
#include "serve/server.h"
#include "serve/viewer.h"
#include "serve_test_client.h"
#include "test_support.h"

namespace npt::serve {
namespace {
namespace fs = std::filesystem;
namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = asio::ip::tcp;
using json = nlohmann::json;

// Object space = the training world, the object's box 1 unit wide and high on the plane z = 0.
nerf::ObjectFrame test_frame() {
    nerf::ObjectFrame f;
    f.object_to_world = Mat4::identity();
    f.box_min = Vec3(-0.5f, -0.5f, 0.0f);
    f.box_max = Vec3(0.5f, 0.5f, 1.0f);
    return f;
}

std::string turntable_bytes() {
    std::string s(100000, '\0');
    for (size_t i = 0; i < s.size(); ++i) s[i] = char(i * 7 + i / 251);
    return s;
}

// A capture's folder as `nerfpt capture` leaves it, with two held-out views.
fs::path make_capture(const fs::path& dir) {
    nerf::NerfConfig c;
    c.encoding.grid.levels = 2;
    c.encoding.grid.log2_table_size = 10;
    c.encoding.finest_resolution = 32;
    c.occupancy.resolution = 8;
    nerf::NerfModel m = nerf::create_model(c, 1.0f, nerf::ngp_world_to_model(0.33f, Vec3(0.5f)));
    std::fill(m.params.begin(), m.params.end(), 0.0f);  // sigma 1 per model unit, colour 0.5 everywhere
    m.training.reset();
    m.object = test_frame();
    nerf::save_model(dir / "model.npt", m, false);
    const json record = {
        {"version", 1},
        {"video", "/videos/Beer.mp4"},
        {"stages",
         {{"curate", {{"kept", 71}, {"decoded", 140}, {"video_frames", 705}, {"seconds", 12.5}}},
          {"poses",
           {{"frames", 71},
            {"registered", 70},
            {"points", 9000},
            {"reprojection_px", 0.7},
            {"path_jumps", 0},
            {"extraction_seconds", 3.0},
            {"matching_seconds", 10.0},
            {"mapping_seconds", 40.0},
            {"seconds", 55.0}}},
          {"object",
           {{"found", true},
            {"up", {0, 0, 1}},
            {"height", 1.0},
            {"metric", false},
            {"plane_inliers", 300},
            {"seed_points", 79},
            {"seconds", 0.5},
            {"model_frame", nerf::object_frame_to_json(test_frame())}}},
          {"split", {{"every", 8}, {"train", 62}, {"test", 2}}},
          {"train", {{"steps", 4117}, {"seconds", 600.0}, {"downscale", 4}, {"width", 32}, {"height", 24}}},
          {"eval", {{"views", 2}, {"psnr", 30.5}, {"ssim", 0.9}, {"seconds", 20.0}}},
          {"turntable",
           {{"file", "turntable.mp4"},
            {"frames", 60},
            {"res", "32x24"},
            {"object", true},
            {"elevation_deg", 30.0},
            {"distance", 3.0},
            {"seconds", 90.0}}}}}};
    test::write_file(dir / "capture.json", record.dump(2));
    test::write_file(dir / "report.md", "# nerfpt capture of /videos/Beer.mp4\n");
    test::write_file(dir / "transforms.json", "{}");
    const json metrics = {{"images",
                           {{{"name", "frame_00004"}, {"frame", 4}, {"psnr", 31.0}, {"ssim", 0.91}},
                            {{"name", "frame_00012"}, {"frame", 12}, {"psnr", nullptr}, {"ssim", 0.89}}}},
                          {"mean", {{"psnr", 30.5}, {"ssim", 0.9}}},
                          {"width", 32},
                          {"height", 24}};
    fs::create_directories(dir / "eval");
    test::write_file(dir / "eval" / "metrics.json", metrics.dump(2));
    Image img(32, 24);
    for (float& p : img.pixels) p = 0.25f;
    Image strip(96, 24);
    for (const char* name : {"frame_00004", "frame_00012"}) {
        write_png(dir / "eval" / (std::string(name) + ".png"), img);
        write_png(dir / "eval" / (std::string(name) + "_compare.png"), strip);
    }
    test::write_file(dir / "turntable.mp4", turntable_bytes());
    return dir;
}

json read_json(const fs::path& p) { return json::parse(test::read_text(p)); }
void write_json(const fs::path& p, const json& j) { test::write_file(p, j.dump(2)); }

TEST(ServeCapture, ReportHasTheStagesMetricsAndFiles) {
    const CaptureReport report(make_capture(test::temp_dir()));
    const json& r = report.report();
    EXPECT_EQ(r["title"], "nerfpt capture of /videos/Beer.mp4");
    ASSERT_EQ(r["stages"].size(), 8u);  // every stage, in order; those not recorded as skipped
    EXPECT_EQ(r["stages"][1]["name"], "poses");
    EXPECT_EQ(r["stages"][1]["state"], "done");
    EXPECT_EQ(r["stages"][1]["seconds"], 55.0);
    EXPECT_EQ(r["stages"][1]["time"],
              "55.0 s (extraction 3.0, matching 10.0, mapping 40.0)");  // as report.md
    EXPECT_NE(r["stages"][1]["note"].get<std::string>().find("registered 70 of 71 frames"),
              std::string::npos);
    EXPECT_EQ(r["stages"][6]["name"], "isolate");
    EXPECT_EQ(r["stages"][6]["state"], "skipped");
    EXPECT_EQ(r["stages"][3]["seconds"], nullptr);                                  // split is not timed
    EXPECT_DOUBLE_EQ(r["total_seconds"].get<double>(), 12.5 + 55 + 600 + 20 + 90);  // object not added
    ASSERT_TRUE(r["eval"].is_object());
    EXPECT_EQ(r["eval"]["views"], 2);
    EXPECT_EQ(r["eval"]["psnr"], 30.5);
    const json& v0 = r["eval"]["images"][0];
    EXPECT_EQ(v0["name"], "frame_00004");
    EXPECT_EQ(v0["psnr"], 31.0);
    EXPECT_EQ(v0["compare"], "/capture/eval/frame_00004_compare.png");
    EXPECT_EQ(v0["render"], "/capture/eval/frame_00004.png");
    EXPECT_EQ(v0["alpha"], nullptr);                     // not written
    EXPECT_EQ(r["eval"]["images"][1]["psnr"], nullptr);  // eval's infinite PSNR
    EXPECT_EQ(r["turntable"]["url"], "/capture/turntable.mp4");
    EXPECT_EQ(r["report_md"], "/capture/report.md");
    EXPECT_TRUE(r["notes"].empty()) << r["notes"];
    ASSERT_TRUE(report.object_frame());
    EXPECT_EQ(report.elevation_deg(), 30.0);
    EXPECT_EQ(report.model().filename(), "model.npt");
}

TEST(ServeCapture, ServesOnlyItsOwnListedFiles) {
    const fs::path dir = make_capture(test::temp_dir());
    // Links, whatever they point to, are not listed: one out of the folder, one to a file of the folder.
    fs::create_symlink("/etc/passwd", dir / "eval" / "passwd.png");
    fs::create_symlink(dir / "capture.json", dir / "eval" / "record.png");
    test::write_file(dir / "eval" / "notes.txt", "not a PNG");
    const CaptureReport report(dir);
    const std::vector<std::string> want = {"/capture/report.json",
                                           "/capture/eval/frame_00004.png",
                                           "/capture/eval/frame_00004_compare.png",
                                           "/capture/eval/frame_00012.png",
                                           "/capture/eval/frame_00012_compare.png",
                                           "/capture/eval/metrics.json",
                                           "/capture/report.md",
                                           "/capture/turntable.mp4"};
    std::vector<std::string> got = report.paths();
    std::sort(got.begin(), got.end());
    std::vector<std::string> sorted = want;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(got, sorted);
    const auto f = report.find("/capture/eval/frame_00004_compare.png");
    ASSERT_TRUE(f);
    EXPECT_EQ(f->content_type, "image/png");
    EXPECT_EQ(f->file, fs::weakly_canonical(dir) / "eval" / "frame_00004_compare.png");
    EXPECT_EQ(report.find("/capture/turntable.mp4")->content_type, "video/mp4");
    for (const char* p :
         {"/capture/capture.json", "/capture/model.npt", "/capture/transforms.json",
          "/capture/eval/passwd.png", "/capture/eval/record.png", "/capture/eval/notes.txt",
          "/capture/../capture.json", "/capture/eval/../report.md", "/capture/eval/../../etc/passwd",
          "/capture//report.md", "/capture/./report.md", "/etc/passwd", "/capture/eval/", "/capture/eval",
          "capture/report.md", "/CAPTURE/report.md"})
        EXPECT_FALSE(report.find(p)) << p;
}

// A folder that is not a capture, or not a finished one, or whose records are malformed: one line naming the
// file and the field.
TEST(ServeCapture, BadFoldersAreOneLineErrors) {
    const fs::path empty = test::temp_dir() / "empty";
    fs::create_directories(empty);
    test::expect_error_message([&] { CaptureReport r(empty); },
                               {"empty", "not a capture folder", "capture.json"});

    const auto variant = [](const std::string& name, auto&& edit) {
        const fs::path dir = test::temp_dir() / name;
        fs::create_directories(dir);
        make_capture(dir);
        edit(dir);
        return dir;
    };
    const auto expect = [&](const std::string& name, auto&& edit, std::initializer_list<std::string> parts) {
        SCOPED_TRACE(name);
        const fs::path dir = variant(name, edit);
        test::expect_error_message([&] { CaptureReport r(dir); }, parts);
    };
    expect("not_json", [](const fs::path& d) { test::write_file(d / "capture.json", "{\"stages\": "); },
           {"capture.json", "not valid JSON"});
    expect("no_stages",
           [](const fs::path& d) {
               write_json(d / "capture.json", {{"version", 1}});
           },
           {"capture.json", "'stages'"});
    expect("version",
           [](const fs::path& d) {
               json j = read_json(d / "capture.json");
               j["version"] = 2;
               write_json(d / "capture.json", j);
           },
           {"capture.json", "'version'", "2"});
    expect("stage_not_object",
           [](const fs::path& d) {
               json j = read_json(d / "capture.json");
               j["stages"]["train"] = 5;
               write_json(d / "capture.json", j);
           },
           {"capture.json", "stages.train"});
    // Unfinished: stopped after poses, no model yet: the first stage not recorded is named.
    expect("unfinished",
           [](const fs::path& d) {
               json j = read_json(d / "capture.json");
               for (const char* s : {"object", "split", "train", "eval", "turntable"}) j["stages"].erase(s);
               write_json(d / "capture.json", j);
               fs::remove(d / "model.npt");
           },
           {"capture.json", "unfinished", "no model.npt", "'object' stage",
            "nerfpt capture /videos/Beer.mp4 -o"});
    expect("model_gone", [](const fs::path& d) { fs::remove(d / "model.npt"); },
           {"model.npt", "'train' stage"});
    expect("turntable_name",
           [](const fs::path& d) {
               json j = read_json(d / "capture.json");
               j["stages"]["turntable"]["file"] = "../../secret.mp4";
               write_json(d / "capture.json", j);
           },
           {"capture.json", "stages.turntable.file", "../../secret.mp4"});
    expect("bad_frame",
           [](const fs::path& d) {
               json j = read_json(d / "capture.json");
               j["stages"]["object"]["model_frame"]["box"] = "big";
               write_json(d / "capture.json", j);
           },
           {"capture.json", "stages.object.model_frame", "box"});
    expect("metrics_name",
           [](const fs::path& d) {
               json j = read_json(d / "eval" / "metrics.json");
               j["images"][1]["name"] = "../../model";
               write_json(d / "eval" / "metrics.json", j);
           },
           {"metrics.json", "images[1].name", "../../model"});
    expect("metrics_psnr",
           [](const fs::path& d) {
               json j = read_json(d / "eval" / "metrics.json");
               j["images"][0]["psnr"] = "high";
               write_json(d / "eval" / "metrics.json", j);
           },
           {"metrics.json", "images[0].psnr"});
    expect("metrics_images",
           [](const fs::path& d) {
               write_json(d / "eval" / "metrics.json", {{"images", 3}});
           },
           {"metrics.json", "'images'"});

    // What a finished capture may lack is said on the page, not refused: no eval/, no turntable file.
    const fs::path lacking = variant("lacking", [](const fs::path& d) {
        fs::remove_all(d / "eval");
        fs::remove(d / "turntable.mp4");
    });
    const CaptureReport r(lacking);
    EXPECT_EQ(r.report()["eval"], nullptr);
    EXPECT_EQ(r.report()["turntable"], nullptr);
    EXPECT_EQ(r.report()["notes"].size(), 2u) << r.report()["notes"];
}

// --- over HTTP
// ------------------------------------------------------------------------------------------------

struct Running {
    std::unique_ptr<Server> server;
    std::thread thread;
    Running(const RouteSource* routes, const std::string& token = {}) {
        ServerOptions so;
        so.port = 0;
        so.token = token;
        so.routes = routes;
        server = std::make_unique<Server>(so);
        thread = std::thread([this] { server->run(); });
    }
    ~Running() {
        server->stop();
        thread.join();
    }
};

http::response<http::string_body> request(uint16_t port, const std::string& target,
                                          const std::string& range = {}, http::verb verb = http::verb::get) {
    asio::io_context ioc;
    beast::tcp_stream stream(ioc);
    tcp::resolver resolver(ioc);
    stream.connect(resolver.resolve("127.0.0.1", std::to_string(port)));
    http::request<http::string_body> req{verb, target, 11};
    req.set(http::field::host, "127.0.0.1:" + std::to_string(port));
    if (!range.empty()) req.set(http::field::range, range);
    http::write(stream, req);
    beast::flat_buffer b;
    http::response_parser<http::string_body> parser;
    parser.skip(verb == http::verb::head);
    parser.body_limit(64 << 20);
    http::read(stream, b, parser);
    return parser.release();
}

TEST(ServeCapture, HttpServesTheReportFilesAndRanges) {
    const fs::path dir = make_capture(test::temp_dir());
    const CaptureReport report(dir);
    Running r(&report);
    const uint16_t port = r.server->port();

    auto res = request(port, "/capture/report.json");
    EXPECT_EQ(res.result_int(), 200);
    EXPECT_EQ(res[http::field::content_type], "application/json");
    EXPECT_EQ(json::parse(res.body()), report.report());
    res = request(port, "/report.html");
    EXPECT_EQ(res.result_int(), 200);
    EXPECT_NE(res.body().find("/report.js"), std::string::npos);
    EXPECT_EQ(request(port, "/stages.js").result_int(), 200);

    res = request(port, "/capture/eval/frame_00004_compare.png");
    EXPECT_EQ(res.result_int(), 200);
    EXPECT_EQ(res[http::field::content_type], "image/png");
    EXPECT_EQ(res.body(), test::read_text(dir / "eval" / "frame_00004_compare.png"));
    EXPECT_EQ(request(port, "/capture/eval/frame%5F00004.png").result_int(), 200);  // escapes are decoded

    // Byte ranges of the video, as a <video> asks for them.
    const std::string video = turntable_bytes();
    const std::string total = std::to_string(video.size());
    res = request(port, "/capture/turntable.mp4");
    EXPECT_EQ(res.result_int(), 200);
    EXPECT_EQ(res[http::field::accept_ranges], "bytes");
    EXPECT_EQ(res[http::field::content_type], "video/mp4");
    EXPECT_EQ(res.body(), video);
    res = request(port, "/capture/turntable.mp4", "bytes=1000-1999");
    EXPECT_EQ(res.result_int(), 206);
    EXPECT_EQ(res[http::field::content_range], "bytes 1000-1999/" + total);
    EXPECT_EQ(res.body(), video.substr(1000, 1000));
    res = request(port, "/capture/turntable.mp4", "bytes=0-");
    EXPECT_EQ(res.result_int(), 206);
    EXPECT_EQ(res.body(), video);
    res = request(port, "/capture/turntable.mp4", "bytes=-10");
    EXPECT_EQ(res.result_int(), 206);
    EXPECT_EQ(res.body(), video.substr(video.size() - 10));
    res = request(port, "/capture/turntable.mp4", "bytes=" + total + "-");
    EXPECT_EQ(res.result_int(), 416);
    EXPECT_EQ(res[http::field::content_range], "bytes */" + total);
    res = request(port, "/capture/turntable.mp4", "bytes=10-19", http::verb::head);
    EXPECT_EQ(res.result_int(), 206);
    EXPECT_EQ(res[http::field::content_length], "10");

    // Traversal, however spelled, and files of the folder the report does not show: 404.
    for (const char* t :
         {"/capture/../capture.json", "/capture/%2e%2e/capture.json", "/capture/eval/..%2f..%2fmodel.npt",
          "/capture/eval/%2e%2e/%2e%2e/etc/passwd", "/capture//capture.json", "/capture/model.npt",
          "/capture/capture.json", "/capture/transforms.json", "/capture/eval/%00.png",
          "/capture/%2Fetc%2Fpasswd", "/../../etc/passwd", "/capture/eval/frame_00004.png/.."})
        EXPECT_EQ(request(port, t).result_int(), 404) << t;

    // A listed file replaced by a link after the listing is not followed.
    fs::remove(dir / "eval" / "frame_00012.png");
    fs::create_symlink(dir / "capture.json", dir / "eval" / "frame_00012.png");
    EXPECT_EQ(request(port, "/capture/eval/frame_00012.png").result_int(), 404);
}

TEST(ServeCapture, TheTokenGuardsTheReportToo) {
    const CaptureReport report(make_capture(test::temp_dir()));
    Running r(&report, "secret");
    EXPECT_EQ(request(r.server->port(), "/capture/report.json").result_int(), 403);
    EXPECT_EQ(request(r.server->port(), "/capture/report.json?token=secret").result_int(), 200);
}

// --- the model in view
// ------------------------------------------------------------------------------------------

// The last frame's pixel (x, y) as 8-bit grey (the mean of R, G, B).
int jpeg_grey(const std::string& jpeg, int x, int y) {
    const std::array<int, 3> p = test::jpeg_pixel(jpeg, x, y);
    return (p[0] + p[1] + p[2]) / 3;
}

TEST(ServeCapture, SceneStandsTheObjectUprightInView) {
    const fs::path dir = make_capture(test::temp_dir());
    const CaptureReport report(dir);
    ModelSceneOptions o;
    o.object = report.object_frame();
    o.elevation_deg = *report.elevation_deg();
    const json scene = model_scene_json("model.npt", o);
    // The cube's local space: the object's box x, z in [-0.5, 0.5], y (up) in [0, 1]; looked at from 30
    // degrees above its centre, Y up, far enough for its bounding sphere to fill the view's 40 degrees.
    EXPECT_EQ(scene["camera"]["look_at"], json({0.0, 0.5, 0.0}));
    EXPECT_EQ(scene["camera"]["up"], json({0, 1, 0}));
    const std::vector<double> p = scene["camera"]["position"];
    const double d = std::hypot(p[0], p[1] - 0.5, p[2]);
    EXPECT_NEAR(d, 1.1 * 0.5 * std::sqrt(3.0) / std::sin(20 * M_PI / 180), 1e-4);
    EXPECT_NEAR(std::asin((p[1] - 0.5) / d) * 180 / M_PI, 30.0, 1e-4);
    EXPECT_FALSE(
        scene["volumes"][0].contains("placement"));  // the default: "object" for a model with a frame

    // Made once beside the model, then kept (the viewer's saves go there).
    const fs::path made = scene_for_model(report.model(), o);
    EXPECT_EQ(made, report.model().parent_path() / "model.serve.json");
    EXPECT_EQ(read_json(made), scene);
    test::write_file(made, "{\"kept\": true}");
    EXPECT_EQ(scene_for_model(report.model(), o), made);
    EXPECT_EQ(test::read_text(made), "{\"kept\": true}");
    fs::remove(made);

    // The viewer renders it: the box, a uniform grey medium, in the middle of the frame; black around it.
    const fs::path s = scene_for_model(report.model(), o);
    Server server(ServerOptions{"127.0.0.1", 0});
    ViewerOptions vo;
    vo.scene = s;
    vo.width = 64;
    vo.height = 48;
    vo.target_spp = 2;
    vo.preview_divisor = 1;
    Viewer viewer(vo, server);
    server.attach(&viewer);
    viewer.start();
    std::thread io([&] { server.run(); });
    {
        test::ServeClient c(server.port());
        c.until("frame", [](const json& f) { return f["spp"] == 2; });
        const int centre = jpeg_grey(c.last_jpeg, 32, 24), corner = jpeg_grey(c.last_jpeg, 2, 2);
        EXPECT_GT(centre, 30) << "the object is not in the middle of the view";
        EXPECT_LT(corner, 8) << "the view's corner is not empty";
    }
    viewer.stop();
    server.stop();
    io.join();
}


// A relightable model served alone gets its capture environment as the scene's sky, turned as the volume turns
// the model: the box placement runs local (= world) x, y, z along model z, x, y (nerf/nerf_placement.h). The
// environment here is radiance (max(d.x, 0), max(d.y, 0), max(d.z, 0)) + 0.01 in model directions, so the sky
// is red toward world +Y, green toward +Z, blue toward +X.
TEST(ServeModelScene, ARelightableModelGetsItsCaptureEnvironmentAsTheSky) {
    nerf::NerfConfig c;
    c.encoding.grid.levels = 2;
    c.encoding.grid.log2_table_size = 10;
    c.occupancy.resolution = 8;
    nerf::NerfModel m = nerf::create_model(c, 1.0f, nerf::ngp_world_to_model(0.33f, Vec3(0.5f)));
    EXPECT_THROW(capture_sky(m), Error);  // not relightable
    nerf::RelightFields f;
    f.config.grid = {2, 2, 10, 4, 1.5f};
    f.config.width = 16;
    f.config.hidden_layers = 1;
    f.params.assign(nerf::make_intrinsic_layout(f.config, m.aabb_scale).total, 0.0f);
    f.capture_env.width = 64;
    f.capture_env.height = 32;
    for (int j = 0; j < 32; ++j)
        for (int i = 0; i < 64; ++i) {
            const Vec3 d = nerf::env_texel_direction(64, 32, i, j);
            f.capture_env.texels.push_back(Rgb(std::max(d.x, 0.0f), std::max(d.y, 0.0f), std::max(d.z, 0.0f)) +
                                           Rgb(0.01f));
        }
    m.relight = f;
    ASSERT_TRUE(m.relightable());
    const Image sky = capture_sky(m, 128, 64);
    const auto at = [&](Vec3 d) {
        const Vec2 uv = lights::equirect_uv(d);
        const float* p = sky.at(std::min(int(uv.x * 128), 127), std::min(int(uv.y * 64), 63));
        return Rgb(p[0], p[1], p[2]);
    };
    // Texel centres lie within 2 degrees of these directions; bilinear taps of a 64x32 map: 0.06 covers both.
    const Rgb up = at(Vec3(0, 1, 0)), z = at(Vec3(0, 0, 1)), x = at(Vec3(1, 0, 0));
    EXPECT_NEAR(up.x, 1.01f, 0.06f);
    EXPECT_NEAR(up.y, 0.01f, 0.06f);
    EXPECT_NEAR(up.z, 0.01f, 0.06f);
    EXPECT_NEAR(z.y, 1.01f, 0.06f);
    EXPECT_NEAR(z.x, 0.01f, 0.06f);
    EXPECT_NEAR(x.z, 1.01f, 0.06f);
    EXPECT_NEAR(x.y, 0.01f, 0.06f);

    // Written beside the model once, and named in the scene's "environment".
    const fs::path dir = test::temp_dir();
    const std::string name = write_capture_sky(dir / "relit.npt", m);
    EXPECT_EQ(name, "relit.capture_sky.exr");
    EXPECT_EQ(read_image(dir / name, false).width, 128);
    EXPECT_EQ(write_capture_sky(dir / "plain.npt", nerf::create_model(c, 1.0f, m.world_to_model)), "");
    ModelSceneOptions o;
    o.environment_file = name;
    EXPECT_EQ(model_scene_json("relit.npt", o)["environment"]["file"], name);
    EXPECT_FALSE(model_scene_json("relit.npt", {}).contains("environment"));
}

}  // namespace
}  // namespace npt::serve
