// COLMAP binary models: files written here by an independent writer (every camera model, known poses and
// points) read back exactly; every kind of bad file refused with a one-line message; the transforms.json
// conversion against poses built by hand (a ring of cameras around a known point) and through our own
// dataset loader; and the real beer capture's reference model, whose reprojection error checks the quaternion
// convention and the intrinsics on data COLMAP made.
#include "capture/colmap_model.h"

#include <gtest/gtest.h>
#include <stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "capture/colmap_runner.h"
#include "capture/transforms_writer.h"
#include "core/error.h"
#include "nerf/dataset.h"
#include "test_support.h"

namespace npt::capture {
namespace {

namespace fs = std::filesystem;

// Little-endian writer, the test's own, so that reader bugs cannot cancel out against a shared writer.
class Bytes {
  public:
    template <typename T>
    Bytes& put(T v) {
        char b[sizeof(T)];
        std::memcpy(b, &v, sizeof(T));
        m_s.append(b, sizeof(T));
        return *this;
    }
    Bytes& str(const std::string& s) {
        m_s.append(s);
        m_s.push_back('\0');
        return *this;
    }
    const std::string& data() const { return m_s; }

  private:
    std::string m_s;
};

std::string cameras_bin(const std::vector<ColmapCamera>& cams) {
    Bytes b;
    b.put<uint64_t>(cams.size());
    for (const auto& c : cams) {
        b.put<int32_t>(c.id).put<int32_t>(int32_t(c.model)).put<uint64_t>(c.width).put<uint64_t>(c.height);
        for (double p : c.params) b.put<double>(p);
    }
    return b.data();
}

std::string images_bin(const std::vector<ColmapImage>& ims) {
    Bytes b;
    b.put<uint64_t>(ims.size());
    for (const auto& im : ims) {
        b.put<int32_t>(im.id);
        for (double q : im.qvec) b.put<double>(q);
        for (double t : im.tvec) b.put<double>(t);
        b.put<int32_t>(im.camera_id).str(im.name).put<uint64_t>(im.points2d.size());
        for (const auto& p : im.points2d) b.put<double>(p.x).put<double>(p.y).put<int64_t>(p.point3d_id);
    }
    return b.data();
}

std::string points_bin(const std::vector<ColmapPoint3D>& pts) {
    Bytes b;
    b.put<uint64_t>(pts.size());
    for (const auto& p : pts) {
        b.put<uint64_t>(p.id);
        for (double v : p.xyz) b.put<double>(v);
        for (uint8_t v : p.rgb) b.put<uint8_t>(v);
        b.put<double>(p.error).put<uint64_t>(p.track.size());
        for (const auto& t : p.track) b.put<int32_t>(t.image_id).put<int32_t>(t.point2d_idx);
    }
    return b.data();
}

void write_model(const fs::path& dir, const ColmapModel& m) {
    test::write_file(dir / "cameras.bin", cameras_bin(m.cameras));
    test::write_file(dir / "images.bin", images_bin(m.images));
    test::write_file(dir / "points3D.bin", points_bin(m.points));
}

using M3 = std::array<Vec3d, 3>;

Vec3d sub(Vec3d a, Vec3d b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(Vec3d a, Vec3d b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3d cross(Vec3d a, Vec3d b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Vec3d normalized(Vec3d a) {
    const double l = std::sqrt(dot(a, a));
    return {a[0] / l, a[1] / l, a[2] / l};
}

// Quaternion (w, x, y, z) of a rotation matrix (Shepperd's method), independent of the reader's conversion.
std::array<double, 4> quat_from_matrix(const M3& r) {
    const double tr = r[0][0] + r[1][1] + r[2][2];
    std::array<double, 4> q;
    if (tr > 0) {
        const double s = 2 * std::sqrt(1 + tr);
        q = {0.25 * s, (r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s, (r[1][0] - r[0][1]) / s};
    } else if (r[0][0] > r[1][1] && r[0][0] > r[2][2]) {
        const double s = 2 * std::sqrt(1 + r[0][0] - r[1][1] - r[2][2]);
        q = {(r[2][1] - r[1][2]) / s, 0.25 * s, (r[0][1] + r[1][0]) / s, (r[0][2] + r[2][0]) / s};
    } else if (r[1][1] > r[2][2]) {
        const double s = 2 * std::sqrt(1 + r[1][1] - r[0][0] - r[2][2]);
        q = {(r[0][2] - r[2][0]) / s, (r[0][1] + r[1][0]) / s, 0.25 * s, (r[1][2] + r[2][1]) / s};
    } else {
        const double s = 2 * std::sqrt(1 + r[2][2] - r[0][0] - r[1][1]);
        q = {(r[1][0] - r[0][1]) / s, (r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s, 0.25 * s};
    }
    return q;
}

// A COLMAP image at `eye` looking at `target` with image-up along `up`: the world-to-camera rows are the
// camera's axes in the world (OpenCV: +X right, +Y down, +Z forward).
ColmapImage look_at(int32_t id, const std::string& name, int32_t camera_id, Vec3d eye, Vec3d target,
                    Vec3d up) {
    const Vec3d z = normalized(sub(target, eye));
    const Vec3d x = normalized(cross(z, up));  // right = forward x up
    const Vec3d y = cross(z, x);
    const M3 r{x, y, z};
    ColmapImage im;
    im.id = id;
    im.name = name;
    im.camera_id = camera_id;
    im.qvec = quat_from_matrix(r);
    for (size_t k = 0; k < 3; ++k) im.tvec[k] = -dot(r[k], eye);
    return im;
}

// Pinhole projection from the look-at axes (not from the quaternion), to fill the 2D observations.
Vec2d pinhole(const ColmapCamera& cam, Vec3d eye, Vec3d target, Vec3d up, Vec3d p) {
    const Vec3d z = normalized(sub(target, eye));
    const Vec3d x = normalized(cross(z, up));
    const Vec3d y = cross(z, x);
    const Vec3d d = sub(p, eye);
    const Intrinsics k = cam.intrinsics();
    return {k.fx * dot(d, x) / dot(d, z) + k.cx, k.fy * dot(d, y) / dot(d, z) + k.cy};
}

ColmapCamera camera(int32_t id, CameraModel model, std::vector<double> params, uint64_t w = 4,
                    uint64_t h = 4) {
    ColmapCamera c;
    c.id = id;
    c.model = model;
    c.width = w;
    c.height = h;
    c.params = std::move(params);
    return c;
}

std::vector<ColmapCamera> every_model() {
    return {camera(1, CameraModel::simple_pinhole, {500, 320, 240}, 640, 480),
            camera(2, CameraModel::pinhole, {500, 510, 321, 241}, 640, 480),
            camera(3, CameraModel::simple_radial, {600, 360, 640, -0.05}, 720, 1280),
            camera(4, CameraModel::radial, {610, 361, 641, -0.04, 0.01}, 720, 1280),
            camera(5, CameraModel::opencv, {700, 705, 400, 300, 0.1, -0.02, 0.001, -0.002}, 800, 600)};
}

// A ring of 4 cameras 2 units from `centre` and 1 above it (along `up`), all looking at the centre, in a
// COLMAP world turned arbitrarily (up is not an axis); 3D points near the centre, each seen by every camera.
struct Ring {
    ColmapModel model;
    Vec3d centre{1, 2, 3};
    Vec3d up = normalized({0.3, -1, 0.2});
    std::vector<Vec3d> eyes;
};

Ring make_ring(bool two_cameras = false) {
    Ring ring;
    const Vec3d a = normalized(cross(ring.up, {1, 0, 0}));
    const Vec3d b = cross(ring.up, a);
    ring.model.cameras.push_back(camera(1, CameraModel::pinhole, {5, 5.5, 2, 2}));
    if (two_cameras) ring.model.cameras.push_back(camera(7, CameraModel::simple_radial, {6, 1.9, 2.1, 0.01}));
    const std::vector<Vec3d> pts{ring.centre, {1.1, 2.2, 2.9}, {0.8, 1.9, 3.1}};
    for (int i = 0; i < 4; ++i) {
        const double t = 0.5 + i * 3.14159265358979 / 2;
        Vec3d eye;
        for (size_t k = 0; k < 3; ++k)
            eye[k] = ring.centre[k] + 2 * (std::cos(t) * a[k] + std::sin(t) * b[k]) + ring.up[k];
        ring.eyes.push_back(eye);
        // Names out of order, so the writer's sort shows.
        const int32_t cam_id = two_cameras && i >= 2 ? 7 : 1;
        ColmapImage im =
            look_at(10 + i, "frame_" + std::to_string(3 - i) + ".png", cam_id, eye, ring.centre, ring.up);
        for (size_t p = 0; p < pts.size(); ++p) {
            const Vec2d px = pinhole(ring.model.cameras[0], eye, ring.centre, ring.up, pts[p]);
            im.points2d.push_back({px[0], px[1], int64_t(p)});
        }
        ring.model.images.push_back(im);
    }
    for (size_t p = 0; p < pts.size(); ++p) {
        ColmapPoint3D pt;
        pt.id = p;
        pt.xyz = pts[p];
        pt.rgb = {uint8_t(p), 20, 30};
        pt.error = 0.5;
        for (int i = 0; i < 4; ++i) pt.track.push_back({10 + i, int32_t(p)});
        ring.model.points.push_back(pt);
    }
    return ring;
}

TEST(ColmapModel, ReadsBackEveryCameraModelImagesAndPoints) {
    const fs::path dir = test::temp_dir();
    Ring ring = make_ring();
    ring.model.cameras = every_model();
    for (auto& im : ring.model.images) im.camera_id = 3;
    ring.model.images[0].points2d.push_back({1.5, 2.5, -1});  // an untriangulated observation
    write_model(dir, ring.model);

    const ColmapModel m = read_colmap_model(dir);
    ASSERT_EQ(m.cameras.size(), 5u);
    for (size_t i = 0; i < 5; ++i) {
        EXPECT_EQ(m.cameras[i].id, ring.model.cameras[i].id);
        EXPECT_EQ(m.cameras[i].model, ring.model.cameras[i].model);
        EXPECT_EQ(m.cameras[i].width, ring.model.cameras[i].width);
        EXPECT_EQ(m.cameras[i].height, ring.model.cameras[i].height);
        EXPECT_EQ(m.cameras[i].params, ring.model.cameras[i].params);
    }
    ASSERT_EQ(m.images.size(), 4u);
    for (size_t i = 0; i < 4; ++i) {
        const auto &a = m.images[i], &b = ring.model.images[i];
        EXPECT_EQ(a.id, b.id);
        EXPECT_EQ(a.name, b.name);
        EXPECT_EQ(a.camera_id, 3);
        EXPECT_EQ(a.qvec, b.qvec);
        EXPECT_EQ(a.tvec, b.tvec);
        ASSERT_EQ(a.points2d.size(), b.points2d.size());
        for (size_t k = 0; k < a.points2d.size(); ++k) {
            EXPECT_EQ(a.points2d[k].x, b.points2d[k].x);
            EXPECT_EQ(a.points2d[k].y, b.points2d[k].y);
            EXPECT_EQ(a.points2d[k].point3d_id, b.points2d[k].point3d_id);
        }
    }
    EXPECT_EQ(m.images[0].points2d.back().point3d_id, -1);
    ASSERT_EQ(m.points.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(m.points[i].id, ring.model.points[i].id);
        EXPECT_EQ(m.points[i].xyz, ring.model.points[i].xyz);
        EXPECT_EQ(m.points[i].rgb, ring.model.points[i].rgb);
        EXPECT_EQ(m.points[i].error, 0.5);
        ASSERT_EQ(m.points[i].track.size(), 4u);
        EXPECT_EQ(m.points[i].track[2].image_id, 12);
        EXPECT_EQ(m.points[i].track[2].point2d_idx, int32_t(i));
    }
}

TEST(ColmapModel, IntrinsicsOfEveryModel) {
    const auto cams = every_model();
    const auto expect = [](const Intrinsics& k, std::array<double, 8> v) {
        EXPECT_EQ(k.fx, v[0]);
        EXPECT_EQ(k.fy, v[1]);
        EXPECT_EQ(k.cx, v[2]);
        EXPECT_EQ(k.cy, v[3]);
        EXPECT_EQ(k.k1, v[4]);
        EXPECT_EQ(k.k2, v[5]);
        EXPECT_EQ(k.p1, v[6]);
        EXPECT_EQ(k.p2, v[7]);
    };
    expect(cams[0].intrinsics(), {500, 500, 320, 240, 0, 0, 0, 0});
    expect(cams[1].intrinsics(), {500, 510, 321, 241, 0, 0, 0, 0});
    expect(cams[2].intrinsics(), {600, 600, 360, 640, -0.05, 0, 0, 0});
    expect(cams[3].intrinsics(), {610, 610, 361, 641, -0.04, 0.01, 0, 0});
    expect(cams[4].intrinsics(), {700, 705, 400, 300, 0.1, -0.02, 0.001, -0.002});
    for (const auto& c : cams) EXPECT_STRNE(camera_model_name(c.model), "unknown");
}

TEST(ColmapModel, QuaternionIsWorldToCameraWxyz) {
    // A quarter turn about +z, (w, x, y, z) = (cos 45, 0, 0, sin 45): world +x lands on camera +y.
    ColmapImage im;
    im.qvec = {std::sqrt(0.5), 0, 0, std::sqrt(0.5)};
    im.tvec = {1, 2, 3};
    const Mat4 w2c = im.world_to_camera();
    test::expect_near(w2c.transform_point({1, 0, 0}), {1, 3, 3});
    const Mat4 back = im.camera_to_world() * w2c;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(back.m[r][c], r == c ? 1 : 0, 1e-12);
}

TEST(ColmapModel, ProjectAppliesOpenCvDistortion) {
    ColmapImage im;  // identity pose: camera coordinates are world coordinates
    const ColmapCamera cam = camera(1, CameraModel::opencv, {100, 110, 50, 60, 0.1, 0.01, 0.001, 0.002});
    // u = 0.1, v = 0.2, r2 = 0.05: radial = 0.005025; du = 0.0005025 + 0.00004 + 0.00014, dv = 0.001005 +
    // 0.00008 + 0.00013.
    const Vec2d px = project(cam, im, {0.2, 0.4, 2});
    EXPECT_NEAR(px[0], 100 * (0.1 + 0.0006825) + 50, 1e-9);
    EXPECT_NEAR(px[1], 110 * (0.2 + 0.001215) + 60, 1e-9);
    const ColmapCamera radial = camera(1, CameraModel::simple_radial, {100, 50, 60, 0.1});
    const Vec2d pr = project(radial, im, {0.2, 0.4, 2});
    EXPECT_NEAR(pr[0], 100 * 0.1 * 1.005 + 50, 1e-9);
    EXPECT_NEAR(pr[1], 100 * 0.2 * 1.005 + 60, 1e-9);
}

TEST(ColmapModel, ReprojectionOfLookAtPosesIsZero) {
    // The observations come from the look-at axes, the projection from the stored quaternion: a wrong
    // quaternion order or a transposed rotation would show here as pixels of error.
    const fs::path dir = test::temp_dir();
    write_model(dir, make_ring().model);
    const ReprojectionStats s = reprojection_error(read_colmap_model(dir));
    EXPECT_EQ(s.observations, 12u);
    EXPECT_LT(s.max_px, 1e-9);
}

TEST(ColmapModel, MissingOrEmptyFiles) {
    const fs::path dir = test::temp_dir();
    test::expect_error_message([&] { read_colmap_model(dir); }, {"cameras.bin", "cannot open"});
    write_model(dir, make_ring().model);
    fs::remove(dir / "points3D.bin");
    test::expect_error_message([&] { read_colmap_model(dir); }, {"points3D.bin", "cannot open"});
    for (const char* f : {"cameras.bin", "images.bin", "points3D.bin"}) {
        write_model(dir, make_ring().model);
        test::write_file(dir / f, "");
        test::expect_error_message([&] { read_colmap_model(dir); }, {f, "truncated", "count"});
    }
}

TEST(ColmapModel, EveryTruncationIsAnError) {
    const Ring ring = make_ring();
    const std::vector<std::pair<std::string, std::string>> files{
        {"cameras.bin", cameras_bin(every_model())},
        {"images.bin", images_bin(ring.model.images)},
        {"points3D.bin", points_bin(ring.model.points)}};
    const fs::path dir = test::temp_dir();
    for (const auto& file : files) {
        const std::string& name = file.first;  // clang 14 cannot capture a structured binding
        const std::string& bytes = file.second;
        // Every prefix, so that each field of each record is cut once.
        for (size_t n = 0; n < bytes.size(); ++n) {
            test::write_file(dir / name, bytes.substr(0, n));
            const auto read = [&] {
                if (name == "cameras.bin") read_cameras_binary(dir / name);
                if (name == "images.bin") read_images_binary(dir / name);
                if (name == "points3D.bin") read_points3d_binary(dir / name);
            };
            SCOPED_TRACE(name + " cut at " + std::to_string(n));
            test::expect_error_message(read, {name});
        }
        test::write_file(dir / name, bytes + "x");
        test::expect_error_message([&] { read_colmap_model(dir); }, {name, "unexpected bytes"});
        test::write_file(dir / name, bytes);
    }
}

TEST(ColmapModel, TruncationMessagesNameTheRecord) {
    const fs::path dir = test::temp_dir();
    const std::string images = images_bin(make_ring().model.images);
    test::write_file(dir / "images.bin", images.substr(0, images.size() - 4));
    // The last image's point count no longer fits: refused at the count, before reading the points.
    test::expect_error_message([&] { read_images_binary(dir / "images.bin"); },
                               {"images.bin", "image 13", "frame_0.png", "num_points2D", "more than"});
    test::write_file(dir / "images.bin", images.substr(0, images.size() - 87));  // inside the last name
    test::expect_error_message([&] { read_images_binary(dir / "images.bin"); },
                               {"images.bin", "truncated", "image 13", "name"});
    const std::string cams = cameras_bin(every_model());
    test::write_file(dir / "cameras.bin", cams.substr(0, cams.size() - 8));
    test::expect_error_message([&] { read_cameras_binary(dir / "cameras.bin"); },
                               {"cameras.bin", "truncated", "camera 5", "params[7]"});
}

TEST(ColmapModel, AbsurdCountsAreRefusedBeforeAllocating) {
    const fs::path dir = test::temp_dir();
    test::write_file(dir / "cameras.bin", Bytes().put<uint64_t>(uint64_t(1) << 60).data());
    test::expect_error_message([&] { read_cameras_binary(dir / "cameras.bin"); },
                               {"cameras.bin", "camera count", "1152921504606846976"});
    // One image whose point count is huge.
    ColmapImage im = make_ring().model.images[0];
    std::string bytes = images_bin({im});
    const size_t count_at = 8 + 4 + 7 * 8 + 4 + im.name.size() + 1;
    const uint64_t huge = ~uint64_t(0);
    std::memcpy(bytes.data() + count_at, &huge, 8);
    test::write_file(dir / "images.bin", bytes);
    test::expect_error_message([&] { read_images_binary(dir / "images.bin"); },
                               {"images.bin", "num_points2D", "frame_3.png"});
    ColmapPoint3D p = make_ring().model.points[0];
    bytes = points_bin({p});
    std::memcpy(bytes.data() + 8 + 8 + 24 + 3 + 8, &huge, 8);
    test::write_file(dir / "points3D.bin", bytes);
    test::expect_error_message([&] { read_points3d_binary(dir / "points3D.bin"); },
                               {"points3D.bin", "point 0", "track_length"});
}

TEST(ColmapModel, BadValuesAreRefused) {
    const fs::path dir = test::temp_dir();
    const fs::path f = dir / "cameras.bin";
    for (int32_t id : {5, 99, -1}) {
        test::write_file(f, Bytes()
                                .put<uint64_t>(1)
                                .put<int32_t>(3)
                                .put<int32_t>(id)
                                .put<uint64_t>(4)
                                .put<uint64_t>(4)
                                .put<double>(1)
                                .put<double>(2)
                                .put<double>(2)
                                .data());
        test::expect_error_message([&] { read_cameras_binary(f); },
                                   {"cameras.bin", "camera 3", "model " + std::to_string(id),
                                    id == 5 ? "OPENCV_FISHEYE" : "unknown", "supported"});
    }
    test::write_file(f, cameras_bin({camera(2, CameraModel::pinhole, {1, 1, 2, 2}, 0, 4)}));
    test::expect_error_message([&] { read_cameras_binary(f); }, {"cameras.bin", "camera 2", "size"});
    test::write_file(f, cameras_bin({camera(2, CameraModel::pinhole, {1, NAN, 2, 2})}));
    test::expect_error_message([&] { read_cameras_binary(f); }, {"cameras.bin", "params[1]", "NaN"});
    test::write_file(f, cameras_bin({camera(2, CameraModel::pinhole, {-1, 1, 2, 2})}));
    test::expect_error_message([&] { read_cameras_binary(f); }, {"cameras.bin", "focal"});

    Ring ring = make_ring();
    ring.model.images[1].tvec[2] = INFINITY;
    test::write_file(dir / "images.bin", images_bin(ring.model.images));
    test::expect_error_message([&] { read_images_binary(dir / "images.bin"); },
                               {"images.bin", "image 11", "tvec"});

    // Files that are each fine but disagree with each other.
    ring = make_ring();
    ring.model.images[2].camera_id = 9;
    write_model(dir, ring.model);
    test::expect_error_message([&] { read_colmap_model(dir); }, {"images.bin", "image 12", "camera 9"});
    ring = make_ring();
    ring.model.points[1].track[0] = {42, 0};
    write_model(dir, ring.model);
    test::expect_error_message([&] { read_colmap_model(dir); }, {"points3D.bin", "point 1", "image 42"});
    ring = make_ring();
    ring.model.points[1].track[0] = {10, 3};
    write_model(dir, ring.model);
    test::expect_error_message([&] { read_colmap_model(dir); }, {"points3D.bin", "point 1", "2D point 3"});
}

Vec3d translation(const Mat4& m) { return {m.m[0][3], m.m[1][3], m.m[2][3]}; }
Vec3d col(const Mat4& m, int c) { return {m.m[0][size_t(c)], m.m[1][size_t(c)], m.m[2][size_t(c)]}; }

TEST(TransformsWriter, RingIsCentredLevelledAndScaled) {
    const Ring ring = make_ring();
    const NerfPoses poses = nerf_poses(ring.model);
    ASSERT_EQ(poses.frames.size(), 4u);
    Vec3d up_sum{0, 0, 0};
    for (size_t i = 0; i < 4; ++i) {
        const PosedFrame& f = poses.frames[i];
        EXPECT_EQ(f.name, "frame_" + std::to_string(i) + ".png");  // sorted by name
        const Vec3d p = translation(f.camera_to_world);
        // Every camera is sqrt(5) from the centre, so each ends at the mean distance, 4.
        EXPECT_NEAR(std::sqrt(dot(p, p)), 4.0, 1e-9);
        // OpenGL: the camera looks down its -Z axis, at the centre of attention, now the origin.
        const Vec3d forward = col(f.camera_to_world, 2);
        for (size_t k = 0; k < 3; ++k) EXPECT_NEAR(-forward[k], -p[k] / 4.0, 1e-9);
        // Cameras 1 above the ring's plane, 2 from its axis: 1/sqrt(5) of the distance is height.
        EXPECT_NEAR(p[2], 4.0 / std::sqrt(5.0), 1e-9);
        for (size_t k = 0; k < 3; ++k) up_sum[k] += f.camera_to_world.m[k][1];
        EXPECT_NEAR(f.camera_to_world.determinant3(), 1.0, 1e-9);
        // The ring's image-up is the world's up, tilted towards the centre by the look-down angle.
        EXPECT_NEAR(f.camera_to_world.m[2][1], 2 / std::sqrt(5.0), 1e-9);
    }
    EXPECT_NEAR(up_sum[0], 0, 1e-9);
    EXPECT_NEAR(up_sum[1], 0, 1e-9);
    // The similarity transform maps the COLMAP centre to the origin and each COLMAP eye onto its frame.
    test::expect_near(poses.world_from_colmap.transform_point({1, 2, 3}), {0, 0, 0}, 1e-6f);
    for (size_t k = 0; k < 3; ++k) EXPECT_NEAR(poses.centre_colmap[k], ring.centre[k], 1e-9);
    for (int i = 0; i < 4; ++i) {
        const Vec3d e = ring.eyes[size_t(i)];
        const Vec3 moved = poses.world_from_colmap.transform_point({float(e[0]), float(e[1]), float(e[2])});
        const Vec3d p = translation(poses.frames[size_t(3 - i)].camera_to_world);
        test::expect_near(moved, {float(p[0]), float(p[1]), float(p[2])}, 1e-5f);
    }
}

TEST(TransformsWriter, RoundTripsThroughTheDatasetLoader) {
    const fs::path dir = test::temp_dir();
    const Ring ring = make_ring(/*two_cameras=*/true);
    fs::create_directories(dir / "frames");
    std::vector<uint8_t> px(4 * 4 * 3, 128);
    for (const auto& im : ring.model.images)
        ASSERT_TRUE(stbi_write_png((dir / "frames" / im.name).string().c_str(), 4, 4, 3, px.data(), 12));
    fs::create_directories(dir / "out");
    TransformsSettings settings;
    settings.images_folder = dir / "frames";
    settings.aabb_scale = 8;
    write_transforms(ring.model, dir / "out" / "transforms.json", settings);

    const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "out" / "transforms.json"));
    EXPECT_EQ(j["aabb_scale"], 8);
    EXPECT_EQ(j["frames"][0]["file_path"], "../frames/frame_0.png");
    EXPECT_FALSE(j.contains("fl_x"));  // two cameras: intrinsics per frame

    const nerf::Dataset ds = nerf::load_dataset(dir / "out" / "transforms.json", "");
    const NerfPoses poses = nerf_poses(ring.model);
    ASSERT_EQ(ds.cameras.size(), 4u);
    EXPECT_EQ(ds.aabb_scale, 8.0f);
    for (size_t i = 0; i < 4; ++i) {
        const auto& c = ds.cameras[i];
        const auto& f = poses.frames[i];
        for (int r = 0; r < 4; ++r)
            for (int k = 0; k < 4; ++k)
                EXPECT_NEAR(c.camera_to_world.m[r][k], f.camera_to_world.m[r][k], 1e-6);
        EXPECT_FLOAT_EQ(c.fx, float(f.intrinsics.fx));
        EXPECT_FLOAT_EQ(c.fy, float(f.intrinsics.fy));
        EXPECT_FLOAT_EQ(c.cx, float(f.intrinsics.cx));
        EXPECT_FLOAT_EQ(c.cy, float(f.intrinsics.cy));
        EXPECT_FLOAT_EQ(c.k1, float(f.intrinsics.k1));
        EXPECT_EQ(c.width, 4);
        EXPECT_EQ(c.height, 4);
    }
    // frame_0 is image 13 on camera 7 (SIMPLE_RADIAL, f = 6); frame_3 is image 10 on camera 1 (fx = 5).
    EXPECT_FLOAT_EQ(ds.cameras[0].fx, 6.0f);
    EXPECT_FLOAT_EQ(ds.cameras[0].k1, 0.01f);
    EXPECT_FLOAT_EQ(ds.cameras[3].fx, 5.0f);
    EXPECT_FLOAT_EQ(ds.cameras[3].fy, 5.5f);
}

TEST(TransformsWriter, OneCameraWritesGlobalIntrinsics) {
    const fs::path dir = test::temp_dir();
    write_transforms(make_ring().model, dir / "transforms.json");
    const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "transforms.json"));
    EXPECT_EQ(j["fl_x"], 5.0);
    EXPECT_EQ(j["fl_y"], 5.5);
    EXPECT_EQ(j["w"], 4);
    EXPECT_NEAR(j["camera_angle_x"].get<double>(), 2 * std::atan(0.4), 1e-12);
    EXPECT_EQ(j["aabb_scale"], 16);
    EXPECT_EQ(j["frames"][3]["file_path"], "images/frame_3.png");
    EXPECT_FALSE(j["frames"][0].contains("fl_x"));
}

// `nerfpt poses --camera-model RADIAL`: one focal length and two radial terms reach transforms.json as
// instant-ngp's colmap2nerf writes them (fl_x = fl_y, k1, k2, no tangential terms) and the trainer's loader.
TEST(TransformsWriter, RadialCameraWritesOneFocalAndBothRadialTerms) {
    const fs::path dir = test::temp_dir();
    Ring ring = make_ring();
    ring.model.cameras[0] = camera(1, CameraModel::radial, {5.25, 2, 2.1, -0.03, 0.004});
    fs::create_directories(dir / "frames");
    std::vector<uint8_t> px(4 * 4 * 3, 128);
    for (const auto& im : ring.model.images)
        ASSERT_TRUE(stbi_write_png((dir / "frames" / im.name).string().c_str(), 4, 4, 3, px.data(), 12));
    TransformsSettings settings;
    settings.images_folder = dir / "frames";
    write_transforms(ring.model, dir / "transforms.json", settings);
    const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "transforms.json"));
    EXPECT_EQ(j["fl_x"], 5.25);
    EXPECT_EQ(j["fl_y"], 5.25);
    EXPECT_EQ(j["cx"], 2.0);
    EXPECT_EQ(j["cy"], 2.1);
    EXPECT_EQ(j["k1"], -0.03);
    EXPECT_EQ(j["k2"], 0.004);
    EXPECT_EQ(j["p1"], 0.0);
    EXPECT_EQ(j["p2"], 0.0);

    const nerf::Dataset ds = nerf::load_dataset(dir / "transforms.json", "");
    ASSERT_EQ(ds.cameras.size(), 4u);
    for (const auto& c : ds.cameras) {
        EXPECT_FLOAT_EQ(c.fx, 5.25f);
        EXPECT_FLOAT_EQ(c.fy, 5.25f);
        EXPECT_FLOAT_EQ(c.k1, -0.03f);
        EXPECT_FLOAT_EQ(c.k2, 0.004f);
        EXPECT_EQ(c.p1, 0.0f);
        EXPECT_EQ(c.p2, 0.0f);
    }
}

TEST(TransformsWriter, BadInput) {
    const fs::path dir = test::temp_dir();
    test::expect_error_message([&] { nerf_poses(ColmapModel{}); }, {"COLMAP model", "no registered image"});
    TransformsSettings s;
    s.aabb_scale = 0;
    test::expect_error_message([&] { write_transforms(make_ring().model, dir / "t.json", s); },
                               {"t.json", "aabb_scale"});
    test::expect_error_message([&] { write_transforms(make_ring().model, dir / "no" / "such" / "t.json"); },
                               {"t.json", "cannot write"});
}

// run_colmap's last step with a stand-in for the colmap tool (a script): its mapper writes the ring (with
// observations moved half a pixel, so the mean error is not zero), its filter copies the model, its bundle
// adjuster copies it too or fails. The refinement's model is used when every step succeeded; when one fails
// the mapper's poses are kept and the run says why, instead of the whole stage failing.
ColmapRun run_with_stand_in(const fs::path& dir, bool adjuster_fails) {
    Ring ring = make_ring();
    for (ColmapImage& im : ring.model.images)
        for (Point2D& p : im.points2d) p.x += 0.5;
    write_model(dir / "mapped", ring.model);
    fs::create_directories(dir / "frames");
    std::vector<uint8_t> px(4 * 4 * 3, 128);
    for (const auto& im : ring.model.images)
        EXPECT_TRUE(stbi_write_png((dir / "frames" / im.name).string().c_str(), 4, 4, 3, px.data(), 12));
    const fs::path tool = dir / "colmap";
    const std::string head = "#!/bin/sh\ncalls='" + (dir / "calls.txt").string() + "'; mapped='" +
                             (dir / "mapped").string() + "'\n";
    const std::string body = R"(echo "$@" >> "$calls"
cmd=$1; shift; in=; out=
while [ $# -gt 1 ]; do case $1 in --input_path) in=$2;; --output_path) out=$2;; esac; shift; done
case $cmd in
  mapper) mkdir -p "$out/0" && cp "$mapped"/*.bin "$out/0/";;
  point_filtering) cp "$in"/*.bin "$out/";;
)";
    const std::string fail = adjuster_fails ? "  bundle_adjuster) echo 'Ceres: no convergence'; exit 3;;\n" : "";
    test::write_file(tool, head + body + fail + "esac\n");
    fs::permissions(tool, fs::perms::owner_all);
    ColmapSettings s;
    s.colmap = tool.string();
    return run_colmap(dir / "frames", dir / "work", s);
}

TEST(ColmapRunner, RefinesTheModelWithTwiceItsMeanError) {
    const fs::path dir = test::temp_dir();
    const ColmapRun run = run_with_stand_in(dir, false);
    EXPECT_TRUE(run.refine_skipped.empty()) << run.refine_skipped;
    EXPECT_EQ(run.model_folder, dir / "work" / "sparse_refined");
    EXPECT_EQ(run.model.images.size(), 4u);
    EXPECT_NEAR(run.refine_error_before_px, 0.5, 1e-6);
    EXPECT_NEAR(run.refine_threshold_px, 1.0, 1e-6);
    const std::string calls = test::read_text(dir / "calls.txt");
    EXPECT_NE(
        calls.find("point_filtering --input_path " + (dir / "work" / "sparse" / "0").string() +
                   " --output_path " + (dir / "work" / "sparse_refined").string() + " --max_reproj_error 1"),
        std::string::npos)
        << calls;
    EXPECT_NE(calls.find("bundle_adjuster"), std::string::npos) << calls;
    EXPECT_GT(run.seconds[4], 0.0);
}

TEST(ColmapRunner, AFailedRefinementKeepsTheMappersPoses) {
    const fs::path dir = test::temp_dir();
    const ColmapRun run = run_with_stand_in(dir, true);
    EXPECT_EQ(run.model_folder, dir / "work" / "sparse" / "0");
    EXPECT_EQ(run.model.images.size(), 4u);
    EXPECT_EQ(run.refine_threshold_px, 0.0);
    EXPECT_NE(run.refine_skipped.find("bundle adjustment failed (exit 3"), std::string::npos)
        << run.refine_skipped;
    EXPECT_NE(run.refine_skipped.find("Ceres: no convergence"), std::string::npos) << run.refine_skipped;
}

TEST(ColmapModel, BeerReferenceModel) {
    const fs::path dir = test::shared_data() / "captures/beer/sparse/0";
    NPT_REQUIRE_SHARED(dir / "images.bin");
    const ColmapModel m = read_colmap_model(dir);
    EXPECT_EQ(m.images.size(), 71u);
    // The reference was made with single_camera=false (its project.ini): one SIMPLE_RADIAL camera per image,
    // each with its own focal length and k.
    ASSERT_EQ(m.cameras.size(), 71u);
    double f_min = 1e30, f_max = 0;
    for (const auto& cam : m.cameras) {
        EXPECT_EQ(cam.model, CameraModel::simple_radial);
        EXPECT_EQ(cam.width, 720u);
        EXPECT_EQ(cam.height, 1280u);
        f_min = std::min(f_min, cam.params[0]);
        f_max = std::max(f_max, cam.params[0]);
    }
    const ColmapCamera& c = m.cameras[0];
    std::string params;
    for (double p : c.params) {
        char buf[32];
        std::snprintf(buf, sizeof buf, " %.6g",
                      p);  // (" " + std::to_string) trips GCC 12's -Wrestrict at -O3
        params += buf;
    }
    const ReprojectionStats s = reprojection_error(m);
    std::printf(
        "beer: camera %d %s %llux%llu params%s (f %.1f..%.1f over %zu cameras); %zu points, %zu "
        "observations, reprojection mean %.4f px, max %.3f px\n",
        c.id, camera_model_name(c.model), (unsigned long long)c.width, (unsigned long long)c.height,
        params.c_str(), f_min, f_max, m.cameras.size(), m.points.size(), s.observations, s.mean_px, s.max_px);
    EXPECT_GT(s.observations, 1000u);
    EXPECT_LT(s.mean_px, 2.0);

    const NerfPoses poses = nerf_poses(m);
    double mean = 0;
    for (const auto& f : poses.frames) {
        const Vec3d p = translation(f.camera_to_world);
        mean += std::sqrt(dot(p, p));
    }
    EXPECT_NEAR(mean / double(poses.frames.size()), 4.0, 1e-9);
}

}  // namespace
}  // namespace npt::capture
