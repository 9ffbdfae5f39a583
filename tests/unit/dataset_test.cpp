// transforms.json loading: a small data set written here (cameras, names, exact pixel bytes), pixel rays
// against hand-computed values, distorted pixel rays against the forward lens model, the camera_angle_x focal
// length, every bad input's message, and the shared lego set.
#include "nerf/dataset.h"

#include <gtest/gtest.h>
#include <stb_image_write.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "core/error.h"
#include "test_support.h"

namespace npt::nerf {
namespace {

namespace fs = std::filesystem;

// A byte pattern that differs per frame, pixel and channel, so a misplaced image or channel shows.
uint8_t pattern(size_t frame, size_t pixel, size_t channel) {
    return uint8_t((frame * 37 + pixel * 11 + channel * 3 + 5) % 256);
}

void write_test_png(const fs::path& path, size_t frame, int w, int h, int channels) {
    std::vector<uint8_t> px(size_t(w) * size_t(h) * size_t(channels));
    for (size_t p = 0; p < size_t(w) * size_t(h); ++p)
        for (size_t c = 0; c < size_t(channels); ++c) px[p * size_t(channels) + c] = pattern(frame, p, c);
    fs::create_directories(path.parent_path());
    ASSERT_NE(stbi_write_png(path.string().c_str(), w, h, channels, px.data(), w * channels), 0);
}

const char* k_identity = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";

// One frame with an identity pose and a 4x3 image, the base that the bad-input tests break one field of.
fs::path write_one_frame(const fs::path& dir, const std::string& frame_extra = "",
                         const std::string& matrix = k_identity, const std::string& global = "\"fl_x\": 5,") {
    write_test_png(dir / "a.png", 0, 4, 3, 4);
    const fs::path json = dir / "transforms.json";
    test::write_file(json, "{" + global + " \"frames\": [{\"file_path\": \"a\", " + frame_extra +
                               "\"transform_matrix\": " + matrix + "}]}");
    return json;
}

TEST(Dataset, LoadsSmallDataset) {
    const fs::path dir = test::temp_dir();
    write_test_png(dir / "a.png", 0, 4, 3, 4);
    write_test_png(dir / "b.png", 1, 4, 3, 4);
    write_test_png(dir / "sub" / "c.png", 2, 4, 3, 3);  // RGB: alpha must come back as 255
    test::write_file(dir / "transforms_train.json", R"({
        "fl_x": 5, "fl_y": 6, "cx": 2.25, "cy": 1.25, "k1": 0.1, "k2": -0.2, "p1": 0.01, "p2": -0.02,
        "aabb_scale": 4,
        "frames": [
          {"file_path": "./a", "transform_matrix": [[1,0,0,1],[0,1,0,2],[0,0,1,3],[0,0,0,1]]},
          {"file_path": "b.png", "fl_x": 7, "transform_matrix": [[0,0,1,-1],[0,1,0,0],[-1,0,0,4],[0,0,0,1]]},
          {"file_path": "sub/c", "transform_matrix": [[1,0,0,0],[0,0,-1,0],[0,1,0,0],[0,0,0,1]]}
        ]})");
    std::vector<size_t> calls;
    const Dataset ds = load_dataset(dir, "train", [&](size_t done, size_t total) {
        EXPECT_EQ(total, 3u);
        calls.push_back(done);
    });
    ASSERT_EQ(ds.cameras.size(), 3u);
    EXPECT_EQ(ds.names, (std::vector<std::string>{"./a", "b.png", "sub/c"}));
    EXPECT_EQ(ds.width, 4);
    EXPECT_EQ(ds.height, 3);
    EXPECT_EQ(ds.aabb_scale, 4.0f);
    EXPECT_FLOAT_EQ(ds.scale, 0.33f);  // instant-ngp's defaults when the json has none
    test::expect_near(ds.offset, Vec3(0.5f, 0.5f, 0.5f), 0.0f);
    EXPECT_EQ(calls, (std::vector<size_t>{1, 2, 3}));  // serialised, so `done` counts up

    const Camera& c0 = ds.cameras[0];
    EXPECT_EQ(c0.fx, 5.0f);
    EXPECT_EQ(c0.fy, 6.0f);
    EXPECT_EQ(c0.cx, 2.25f);
    EXPECT_EQ(c0.cy, 1.25f);
    EXPECT_EQ(c0.width, 4);
    EXPECT_EQ(c0.height, 3);
    EXPECT_FLOAT_EQ(c0.k1, 0.1f);
    EXPECT_FLOAT_EQ(c0.k2, -0.2f);
    EXPECT_FLOAT_EQ(c0.p1, 0.01f);
    EXPECT_FLOAT_EQ(c0.p2, -0.02f);
    EXPECT_EQ(c0.camera_to_world.m[0][3], 1.0);
    EXPECT_EQ(c0.camera_to_world.m[2][3], 3.0);
    EXPECT_EQ(ds.cameras[1].fx, 7.0f);  // the frame's value wins over the global one
    EXPECT_EQ(ds.cameras[1].fy, 6.0f);
    EXPECT_EQ(ds.cameras[1].camera_to_world.m[2][0], -1.0);
    EXPECT_EQ(ds.cameras[2].camera_to_world.m[1][2], -1.0);

    ASSERT_EQ(ds.rgba.size(), 3u * 4 * 3 * 4);
    for (size_t f = 0; f < 3; ++f)
        for (size_t p = 0; p < 12; ++p)
            for (size_t c = 0; c < 4; ++c) {
                const uint8_t want = (f == 2 && c == 3) ? 255 : pattern(f, p, c);
                ASSERT_EQ(ds.image(f)[p * 4 + c], want)
                    << "frame " << f << " pixel " << p << " channel " << c;
            }
}

TEST(Dataset, JsonFileGivenDirectly) {
    const fs::path dir = test::temp_dir();
    const fs::path json = write_one_frame(dir);
    const Dataset ds = load_dataset(json, "ignored");
    EXPECT_EQ(ds.cameras.size(), 1u);
    // A folder with an empty split reads transforms.json.
    EXPECT_EQ(load_dataset(dir, "").cameras.size(), 1u);
}

TEST(Dataset, PixelRay) {
    Camera cam;
    cam.fx = 5;
    cam.fy = 6;
    cam.cx = 2;
    cam.cy = 1.5f;
    cam.width = 4;
    cam.height = 3;
    // 90 degrees about +Y (camera -Z looks down world -X), then a move to (1, 2, 3).
    cam.camera_to_world.m = {{{0, 0, 1, 1}, {0, 1, 0, 2}, {-1, 0, 0, 3}, {0, 0, 0, 1}}};

    const Ray centre = generate_pixel_ray(cam, cam.cx, cam.cy);
    test::expect_near(centre.o, Vec3(1, 2, 3), 0.0f);
    test::expect_near(centre.d, Vec3(-1, 0, 0), 1e-6f);  // the camera's -Z axis in world space

    // The top-left pixel's centre: camera direction ((0.5-2)/5, -(0.5-1.5)/6, -1) = (-0.3, 1/6, -1), which
    // the rotation maps to (z, y, -x) = (-1, 1/6, 0.3).
    const Ray corner = generate_pixel_ray(cam, 0.5f, 0.5f);
    const float len = std::sqrt(1.0f + 1.0f / 36.0f + 0.09f);
    test::expect_near(corner.o, Vec3(1, 2, 3), 0.0f);
    test::expect_near(corner.d, Vec3(-1.0f / len, (1.0f / 6.0f) / len, 0.3f / len), 1e-6f);
}

// A phone-like camera (1920x1080, ~65 degrees across, principal point off centre) at a pose with no special
// axes, so a swapped sign or axis in the distortion shows.
Camera phone_camera(float k1, float k2, float p1, float p2) {
    Camera cam;
    cam.width = 1920;
    cam.height = 1080;
    cam.fx = 1510.5f;
    cam.fy = 1508.25f;
    cam.cx = 961.3f;
    cam.cy = 538.7f;
    cam.k1 = k1;
    cam.k2 = k2;
    cam.p1 = p1;
    cam.p2 = p2;
    // Unit quaternion (0.2, -0.4, 0.1, w) and a move to (0.5, -1, 2).
    const double qx = 0.2, qy = -0.4, qz = 0.1, qw = std::sqrt(1.0 - 0.04 - 0.16 - 0.01);
    cam.camera_to_world = Mat4::translation(0.5, -1, 2) * Mat4::rotation_quat(qx, qy, qz, qw);
    return cam;
}

// The forward model: world -> OpenGL camera -> OpenCV normalised (y down) -> distorted -> pixel.
Vec2 project_distorted(const Camera& cam, Vec3 p) {
    const Vec3 q = cam.camera_to_world.inverse().transform_point(p);
    const double u = q.x / -q.z, v = -q.y / -q.z;
    double ud, vd;
    distort(cam.distortion(), u, v, &ud, &vd);
    return Vec2(float(cam.cx + cam.fx * ud), float(cam.cy + cam.fy * vd));
}

// Angle between the ray's direction and the direction from its origin to p, in radians.
double angle_to(const Ray& r, Vec3 p) {
    const Vec3 to = p - r.o;
    const double dx = to.x, dy = to.y, dz = to.z;
    const double cx = r.d.y * dz - r.d.z * dy, cy = r.d.z * dx - r.d.x * dz, cz = r.d.x * dy - r.d.y * dx;
    return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), r.d.x * dx + r.d.y * dy + r.d.z * dz);
}

TEST(Dataset, PixelRayUndistortsThroughTheProjectedPoint) {
    const Camera pinhole = phone_camera(0, 0, 0, 0);
    const Vec3 o = pinhole.camera_to_world.transform_point(Vec3(0.0f, 0.0f, 0.0f));
    // The coefficients of a real phone clip (COLMAP's OPENCV model) and a stronger barrel lens with
    // tangential terms.
    for (const Camera& cam :
         {phone_camera(0.0317f, -0.0498f, 4e-4f, -6e-4f), phone_camera(-0.1f, 0.02f, 1e-3f, -1e-3f)}) {
        double pinhole_worst = 0;
        int seen = 0;
        // Points in front of the camera over the whole frame, corners included, at several depths.
        for (double a : {-0.6, -0.3, 0.0, 0.25, 0.62})
            for (double b : {-0.34, -0.1, 0.0, 0.2, 0.35})
                for (double depth : {0.7, 3.0, 25.0}) {
                    const Vec3 p = pinhole.camera_to_world.transform_point(
                        Vec3(float(a * depth), float(b * depth), float(-depth)));
                    const Vec2 px = project_distorted(cam, p);
                    ASSERT_TRUE(px.x > 0 && px.x < cam.width && px.y > 0 && px.y < cam.height)
                        << a << " " << b;
                    const Ray r = generate_pixel_ray(cam, px.x, px.y);
                    test::expect_near(r.o, o, 0.0f);
                    EXPECT_LT(angle_to(r, p), 1e-5) << "point (" << a << ", " << b << ") at depth " << depth;
                    pinhole_worst =
                        std::max(pinhole_worst, angle_to(generate_pixel_ray(pinhole, px.x, px.y), p));
                    ++seen;
                }
        EXPECT_EQ(seen, 75);
        // Ignoring the lens misses by 50x the tolerance or more (the phone lens moves corners by ~3 pixels):
        // the test would notice distortion not being applied.
        EXPECT_GT(pinhole_worst, 5e-4) << "k1 " << cam.k1;
    }
}

TEST(Dataset, PixelRayWithoutDistortionIsThePinholeRayExactly) {
    const Camera cam = phone_camera(0, 0, 0, 0);
    for (float px : {0.5f, 17.25f, 960.5f, 1919.5f})
        for (float py : {0.5f, 333.75f, 1079.5f}) {
            // The pinhole formula generate_pixel_ray used before distortion was applied, bit for bit.
            const Vec3 d_cam((px - cam.cx) / cam.fx, -(py - cam.cy) / cam.fy, -1.0f);
            const Vec3 want = normalize(cam.camera_to_world.transform_vector(d_cam));
            const Ray r = generate_pixel_ray(cam, px, py);
            EXPECT_EQ(r.d.x, want.x);
            EXPECT_EQ(r.d.y, want.y);
            EXPECT_EQ(r.d.z, want.z);
        }
}

TEST(Dataset, DistortionPerFrameOverridesGlobal) {
    // instant-ngp writes k1, k2, p1, p2 at the top level (one shared camera) or in each frame.
    const fs::path dir = test::temp_dir();
    write_one_frame(dir, "\"k1\": 0.03, \"p2\": -0.001, ", k_identity,
                    "\"fl_x\": 5, \"k1\": 0.5, \"k2\": -0.05, \"p1\": 0.002,");
    const Camera c = load_dataset(dir, "").cameras[0];
    EXPECT_FLOAT_EQ(c.k1, 0.03f);
    EXPECT_FLOAT_EQ(c.k2, -0.05f);
    EXPECT_FLOAT_EQ(c.p1, 0.002f);
    EXPECT_FLOAT_EQ(c.p2, -0.001f);
}

TEST(Dataset, CameraAngleGivesFocalLength) {
    const fs::path dir = test::temp_dir();
    const double ax = 0.75, ay = 0.5;  // exact in std::to_string's 6 decimals
    write_one_frame(
        dir, "", k_identity,
        "\"camera_angle_x\": " + std::to_string(ax) + ", \"camera_angle_y\": " + std::to_string(ay) + ",");
    const Camera c = load_dataset(dir, "").cameras[0];
    EXPECT_FLOAT_EQ(c.fx, float(0.5 * 4 / std::tan(0.5 * ax)));
    EXPECT_FLOAT_EQ(c.fy, float(0.5 * 3 / std::tan(0.5 * ay)));
    EXPECT_EQ(c.cx, 2.0f);  // principal point defaults to the image centre
    EXPECT_EQ(c.cy, 1.5f);

    // Without camera_angle_y pixels are square.
    const fs::path dir2 = test::temp_dir() / "x";
    write_one_frame(dir2, "", k_identity, "\"camera_angle_x\": " + std::to_string(ax) + ",");
    const Camera c2 = load_dataset(dir2, "").cameras[0];
    EXPECT_EQ(c2.fy, c2.fx);
}

TEST(Dataset, BadInputs) {
    const fs::path dir = test::temp_dir();
    auto load = [](const fs::path& p) { return [p] { load_dataset(p, ""); }; };

    test::expect_error_message([&] { load_dataset(dir, "val"); }, {"transforms_val.json", "file not found"});

    test::write_file(dir / "bad" / "transforms.json", "{\"frames\": [");
    test::expect_error_message(load(dir / "bad"), {"transforms.json", "not valid JSON"});

    test::write_file(dir / "empty" / "transforms.json", "{\"fl_x\": 5, \"frames\": []}");
    test::expect_error_message(load(dir / "empty"), {"transforms.json", "'frames' is empty"});
    test::write_file(dir / "noframes" / "transforms.json", "{\"fl_x\": 5}");
    test::expect_error_message(load(dir / "noframes"), {"transforms.json", "missing 'frames'"});

    write_one_frame(dir / "nomat", "", "null");
    test::write_file(dir / "nomat" / "transforms.json", R"({"fl_x": 5, "frames": [{"file_path": "a"}]})");
    test::expect_error_message(load(dir / "nomat"),
                               {"transforms.json", "frame 0 ('a')", "'transform_matrix'"});

    write_one_frame(dir / "shape", "", "[[1,0,0,0],[0,1,0,0],[0,0,1,0]]");
    test::expect_error_message(load(dir / "shape"), {"transforms.json", "frame 0", "4x4"});
    write_one_frame(dir / "type", "", "[[1,0,0,0],[0,1,0,0],[0,0,1,\"x\"],[0,0,0,1]]");
    test::expect_error_message(load(dir / "type"), {"transforms.json", "frame 0", "4x4"});

    // JSON has no NaN: nlohmann writes it as null, Python as a bare NaN (not JSON); an overflowing literal
    // would be Inf, which nlohmann refuses while parsing.
    write_one_frame(dir / "nan", "", "[[1,0,0,0],[0,null,0,0],[0,0,1,0],[0,0,0,1]]");
    test::expect_error_message(load(dir / "nan"), {"transforms.json", "frame 0", "NaN", "row 1, column 1"});
    write_one_frame(dir / "pynan", "", "[[1,0,0,0],[0,NaN,0,0],[0,0,1,0],[0,0,0,1]]");
    test::expect_error_message(load(dir / "pynan"), {"transforms.json", "not valid JSON"});
    write_one_frame(dir / "inf", "", "[[1,0,0,0],[0,1,0,0],[0,0,1,1e999],[0,0,0,1]]");
    test::expect_error_message(load(dir / "inf"), {"transforms.json", "not valid JSON", "1e999"});

    write_one_frame(dir / "nointr", "", k_identity, "");
    test::expect_error_message(
        load(dir / "nointr"), {"transforms.json", "frame 0", "missing intrinsics", "fl_x", "camera_angle_x"});
    write_one_frame(dir / "strfl", "", k_identity, "\"fl_x\": \"5\",");
    test::expect_error_message(load(dir / "strfl"), {"transforms.json", "'fl_x' must be a number"});

    write_one_frame(dir / "noimg");
    test::write_file(
        dir / "noimg" / "transforms.json",
        std::string(R"({"fl_x": 5, "frames": [{"file_path": "./missing", "transform_matrix": )") +
            k_identity + "}]}");
    test::expect_error_message(load(dir / "noimg"),
                               {"transforms.json", "frame 0 ('./missing')", "image not found", "missing.png",
                                "missing.jpg", "missing.jpeg"});

    // A second frame of another size: the message names that frame and both sizes.
    write_one_frame(dir / "size");
    write_test_png(dir / "size" / "b.png", 1, 5, 3, 4);
    test::write_file(dir / "size" / "transforms.json",
                     std::string(R"({"fl_x": 5, "frames": [{"file_path": "a", "transform_matrix": )") +
                         k_identity + R"(}, {"file_path": "b", "transform_matrix": )" + k_identity + "}]}");
    test::expect_error_message(load(dir / "size"),
                               {"transforms.json", "frame 1 ('b')", "b.png", "5x3", "first frame's is 4x3"});

    // 'w'/'h' that disagree with the image.
    write_one_frame(dir / "wh", "\"w\": 8, ", k_identity);
    test::expect_error_message(load(dir / "wh"), {"transforms.json", "frame 0", "'w'/'h'", "8x3"});

    // Zero-size images: an empty file, and a PNG whose header says 0 pixels wide (stb does not check CRCs;
    // its '0-pixel image' reason is overwritten by the other decoders it tries).
    write_one_frame(dir / "zero");
    test::write_file(dir / "zero" / "a.png", "");
    test::expect_error_message(load(dir / "zero"), {"transforms.json", "frame 0", "a.png", "empty"});
    const std::string zero_png = std::string("\x89PNG\r\n\x1a\n", 8) + std::string("\0\0\0\x0dIHDR", 8) +
                                 std::string("\0\0\0\0\0\0\0\x03\x08\x06\0\0\0", 13) + std::string(4, '\0');
    test::write_file(dir / "zero" / "a.png", zero_png);
    test::expect_error_message(load(dir / "zero"),
                               {"transforms.json", "frame 0", "a.png", "not a readable image"});
}

// Poses, scale and lens coefficients that would train, evaluate or render nonsense silently.
TEST(Dataset, BadPosesScaleAndLens) {
    const fs::path dir = test::temp_dir();
    auto load = [](const fs::path& p) { return [p] { load_dataset(p, ""); }; };

    write_one_frame(dir / "zero", "", "[[0,0,0,0],[0,0,0,0],[0,0,0,0],[0,0,0,0]]");
    test::expect_error_message(load(dir / "zero"),
                               {"transforms.json", "frame 0", "'transform_matrix'", "last row"});
    write_one_frame(dir / "zero3", "", "[[0,0,0,1],[0,0,0,2],[0,0,0,3],[0,0,0,1]]");
    test::expect_error_message(load(dir / "zero3"), {"transforms.json", "frame 0", "not invertible"});
    write_one_frame(dir / "flat", "", "[[1,0,1,0],[0,1,0,0],[0,0,0,0],[0,0,0,1]]");  // z axis = x axis
    test::expect_error_message(load(dir / "flat"), {"transforms.json", "frame 0", "not invertible"});
    write_one_frame(dir / "far", "", "[[1,0,0,1e300],[0,1,0,0],[0,0,1,0],[0,0,0,1]]");
    test::expect_error_message(load(dir / "far"),
                               {"transforms.json", "frame 0", "beyond the range of a float"});

    write_one_frame(dir / "scale0", "", k_identity, "\"fl_x\": 5, \"scale\": 0,");
    test::expect_error_message(load(dir / "scale0"),
                               {"transforms.json", "'scale' must be a positive number"});
    write_one_frame(dir / "scaleneg", "", k_identity, "\"fl_x\": 5, \"scale\": -0.33,");
    test::expect_error_message(load(dir / "scaleneg"), {"transforms.json", "'scale'"});
    write_one_frame(dir / "aabb", "", k_identity, "\"fl_x\": 5, \"aabb_scale\": 1e9,");
    test::expect_error_message(load(dir / "aabb"), {"transforms.json", "'aabb_scale' must be in (0, 128]"});
    write_one_frame(dir / "fl", "", k_identity, "\"fl_x\": 1e300,");
    test::expect_error_message(load(dir / "fl"), {"transforms.json", "frame 0", "do not fit a float"});

    write_one_frame(dir / "k1", "", k_identity, "\"fl_x\": 5, \"k1\": 1e30,");
    test::expect_error_message(load(dir / "k1"),
                               {"transforms.json", "frame 0", "'k1'", "1e+30", "cannot be undistorted"});
    write_one_frame(dir / "k1big", "\"k1\": 1e39, ", k_identity);
    test::expect_error_message(load(dir / "k1big"), {"transforms.json", "frame 0", "must fit a float"});
    // A strong but plausible lens (a wide phone camera) still loads.
    write_one_frame(dir / "k1ok", "", k_identity, "\"fl_x\": 5, \"k1\": -0.3, \"k2\": 0.1, \"p1\": 0.001,");
    EXPECT_NO_THROW(load_dataset(dir / "k1ok", ""));
}

TEST(Dataset, LegoTrainSplit) {
    const fs::path lego = test::shared_data() / "nerf_synthetic" / "lego";
    NPT_REQUIRE_SHARED(lego / "transforms_train.json");
    const auto t0 = std::chrono::steady_clock::now();
    const Dataset ds = load_dataset(lego, "train");
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    RecordProperty("load_seconds", std::to_string(seconds));
    std::printf("lego train: 100 frames loaded in %.2f s\n", seconds);

    ASSERT_EQ(ds.cameras.size(), 100u);
    EXPECT_EQ(ds.width, 400);
    EXPECT_EQ(ds.height, 400);
    EXPECT_EQ(ds.rgba.size(), 100u * 400 * 400 * 4);
    EXPECT_EQ(ds.names[0], "./train/r_0");
    const Camera& c = ds.cameras[0];
    // fx = 0.5 * 400 / tan(0.5 * camera_angle_x); float rounding of the result is the tolerance.
    const double fx = 0.5 * 400 / std::tan(0.5 * 0.6911112070083618);
    EXPECT_NEAR(c.fx, fx, 1e-6 * fx);
    EXPECT_NEAR(c.fx, 555.555, 0.01);
    EXPECT_EQ(c.fy, c.fx);
    // The matrix's last column as written in transforms_train.json, frame 0.
    EXPECT_DOUBLE_EQ(c.camera_to_world.m[0][3], -0.05379832163453102);
    EXPECT_DOUBLE_EQ(c.camera_to_world.m[1][3], 3.845470428466797);
    EXPECT_DOUBLE_EQ(c.camera_to_world.m[2][3], 1.2080823183059692);
    const Ray r = generate_pixel_ray(c, c.cx, c.cy);
    test::expect_near(r.o,
                      Vec3(float(c.camera_to_world.m[0][3]), float(c.camera_to_world.m[1][3]),
                           float(c.camera_to_world.m[2][3])),
                      0.0f);
    // NeRF-synthetic renders have a transparent background: some alpha must be 0, some 255.
    bool has_clear = false, has_opaque = false;
    for (size_t p = 0; p < 400 * 400; ++p) {
        has_clear |= ds.image(0)[4 * p + 3] == 0;
        has_opaque |= ds.image(0)[4 * p + 3] == 255;
    }
    EXPECT_TRUE(has_clear && has_opaque);
}

}  // namespace
}  // namespace npt::nerf
