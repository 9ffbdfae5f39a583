// COLMAP binary model reader. The files are read whole (a sparse model is a few MB) and parsed through a
// cursor that checks every read against the bytes left, so a truncated or corrupt file is a one-line error.
#include "capture/colmap_model.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <unordered_map>

#include "core/error.h"

namespace npt::capture {
namespace {

namespace fs = std::filesystem;

std::string read_whole_file(const fs::path& file) {
    std::error_code ec;
    if (fs::exists(file, ec) && !fs::is_regular_file(file, ec))  // a FIFO would block forever
        throw Error(file.string() + ": not a regular file");
    std::ifstream in(file, std::ios::binary);
    if (!in) throw Error(file.string() + ": cannot open (missing or unreadable)");
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw Error(file.string() + ": read error");
    return bytes;
}

// Little-endian reads (COLMAP writes host order, and every platform it runs on is little-endian) that name
// the record being read when the file ends early.
class Cursor {
  public:
    Cursor(const fs::path& file, const std::string& bytes) : m_file(file.string()), m_bytes(bytes) {}

    size_t left() const { return m_bytes.size() - m_pos; }
    const std::string& file() const { return m_file; }

    // `record` names what is being read (e.g. "image 3, field 'tvec'") for the error message.
    template <typename T>
    T read(const std::string& record) {
        need(sizeof(T), record);
        T v;
        std::memcpy(&v, m_bytes.data() + m_pos, sizeof(T));
        m_pos += sizeof(T);
        return v;
    }

    double read_finite(const std::string& record) {
        const double v = read<double>(record);
        if (!std::isfinite(v)) throw Error(m_file + ": " + record + " is NaN or Inf");
        return v;
    }

    std::string read_cstring(const std::string& record) {
        const size_t end = m_bytes.find('\0', m_pos);
        if (end == std::string::npos)
            throw Error(m_file + ": truncated in " + record +
                        " (no terminating NUL before the end of the file)");
        std::string s = m_bytes.substr(m_pos, end - m_pos);
        m_pos = end + 1;
        return s;
    }

    // A count read from the file, refused when `count` records of at least `min_record_bytes` each cannot fit
    // in what is left: this keeps a corrupt count from allocating gigabytes.
    uint64_t read_count(const std::string& record, size_t min_record_bytes) {
        const uint64_t n = read<uint64_t>(record);
        if (min_record_bytes > 0 && n > left() / min_record_bytes)
            throw Error(m_file + ": " + record + " is " + std::to_string(n) + ", more than the " +
                        std::to_string(left()) + " bytes left in the file can hold");
        return n;
    }

    void need(size_t n, const std::string& record) const {
        if (n > left())
            throw Error(m_file + ": truncated in " + record + " (needs " + std::to_string(n) + " bytes, " +
                        std::to_string(left()) + " left)");
    }

    void expect_end() const {
        if (left() != 0)
            throw Error(m_file + ": " + std::to_string(left()) + " unexpected bytes after the last record");
    }

  private:
    std::string m_file;
    const std::string& m_bytes;
    size_t m_pos = 0;
};

bool supported_model_id(int32_t id) { return id >= 0 && id <= 4; }

// COLMAP's names for the models nerfpt refuses, so that the message says what the model is.
const char* unsupported_model_name(int32_t id) {
    switch (id) {
        case 5:
            return "OPENCV_FISHEYE";
        case 6:
            return "FULL_OPENCV";
        case 7:
            return "FOV";
        case 8:
            return "SIMPLE_RADIAL_FISHEYE";
        case 9:
            return "RADIAL_FISHEYE";
        case 10:
            return "THIN_PRISM_FISHEYE";
        default:
            return "unknown";
    }
}

Mat4 rotation_translation(const std::array<double, 4>& q_in, const Vec3d& t) {
    // COLMAP stores unit quaternions; normalising keeps a slightly denormalised one a rotation.
    const double n = std::sqrt(q_in[0] * q_in[0] + q_in[1] * q_in[1] + q_in[2] * q_in[2] + q_in[3] * q_in[3]);
    const double w = q_in[0] / n, x = q_in[1] / n, y = q_in[2] / n, z = q_in[3] / n;
    Mat4 m;
    m.m[0] = {1 - 2 * y * y - 2 * z * z, 2 * x * y - 2 * w * z, 2 * x * z + 2 * w * y, t[0]};
    m.m[1] = {2 * x * y + 2 * w * z, 1 - 2 * x * x - 2 * z * z, 2 * y * z - 2 * w * x, t[1]};
    m.m[2] = {2 * x * z - 2 * w * y, 2 * y * z + 2 * w * x, 1 - 2 * x * x - 2 * y * y, t[2]};
    m.m[3] = {0, 0, 0, 1};
    return m;
}

}  // namespace

const char* camera_model_name(CameraModel model) {
    switch (model) {
        case CameraModel::simple_pinhole:
            return "SIMPLE_PINHOLE";
        case CameraModel::pinhole:
            return "PINHOLE";
        case CameraModel::simple_radial:
            return "SIMPLE_RADIAL";
        case CameraModel::radial:
            return "RADIAL";
        case CameraModel::opencv:
            return "OPENCV";
    }
    return "unknown";
}

int camera_model_param_count(CameraModel model) {
    switch (model) {
        case CameraModel::simple_pinhole:
            return 3;
        case CameraModel::pinhole:
            return 4;
        case CameraModel::simple_radial:
            return 4;
        case CameraModel::radial:
            return 5;
        case CameraModel::opencv:
            return 8;
    }
    return 0;
}

Intrinsics ColmapCamera::intrinsics() const {
    const auto& p = params;
    Intrinsics k;
    switch (model) {
        case CameraModel::simple_pinhole:
            k = {p[0], p[0], p[1], p[2]};
            break;
        case CameraModel::pinhole:
            k = {p[0], p[1], p[2], p[3]};
            break;
        case CameraModel::simple_radial:
            k = {p[0], p[0], p[1], p[2], p[3]};
            break;
        case CameraModel::radial:
            k = {p[0], p[0], p[1], p[2], p[3], p[4]};
            break;
        case CameraModel::opencv:
            k = {p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]};
            break;
    }
    return k;
}

Mat4 ColmapImage::world_to_camera() const { return rotation_translation(qvec, tvec); }

Mat4 ColmapImage::camera_to_world() const {
    // Inverse of a rigid transform: R^T and -R^T t, exact where a general inverse would round.
    const Mat4 w2c = world_to_camera();
    Mat4 c2w;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) c2w.m[r][c] = w2c.m[c][r];
        c2w.m[r][3] = -(w2c.m[0][r] * tvec[0] + w2c.m[1][r] * tvec[1] + w2c.m[2][r] * tvec[2]);
    }
    return c2w;
}

const ColmapCamera* ColmapModel::find_camera(int32_t id) const {
    for (const auto& c : cameras)
        if (c.id == id) return &c;
    return nullptr;
}

const ColmapImage* ColmapModel::find_image(int32_t id) const {
    for (const auto& im : images)
        if (im.id == id) return &im;
    return nullptr;
}

std::vector<ColmapCamera> read_cameras_binary(const fs::path& file) {
    const std::string bytes = read_whole_file(file);
    Cursor in(file, bytes);
    // The smallest camera record: id, model, width, height and SIMPLE_PINHOLE's 3 parameters.
    const uint64_t n = in.read_count("the camera count", 4 + 4 + 8 + 8 + 3 * 8);
    std::vector<ColmapCamera> cameras(n);
    for (uint64_t i = 0; i < n; ++i) {
        ColmapCamera& c = cameras[i];
        const std::string rec = "camera " + std::to_string(i);
        c.id = in.read<int32_t>(rec + ", field 'camera_id'");
        const std::string named = "camera " + std::to_string(c.id);
        const int32_t model_id = in.read<int32_t>(named + ", field 'model_id'");
        if (!supported_model_id(model_id))
            throw Error(in.file() + ": " + named + " uses camera model " + std::to_string(model_id) + " (" +
                        unsupported_model_name(model_id) +
                        "); supported: SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV (run COLMAP's "
                        "feature_extractor with --ImageReader.camera_model set to one of them)");
        c.model = CameraModel(model_id);
        c.width = in.read<uint64_t>(named + ", field 'width'");
        c.height = in.read<uint64_t>(named + ", field 'height'");
        constexpr uint64_t k_max_side = uint64_t(1) << 20;
        if (c.width == 0 || c.height == 0 || c.width > k_max_side || c.height > k_max_side)
            throw Error(in.file() + ": " + named + " has image size " + std::to_string(c.width) + "x" +
                        std::to_string(c.height) + " (must be 1.." + std::to_string(k_max_side) + ")");
        const int np = camera_model_param_count(c.model);
        c.params.resize(size_t(np));
        for (int k = 0; k < np; ++k)
            c.params[size_t(k)] = in.read_finite(named + ", field 'params[" + std::to_string(k) + "]'");
        const Intrinsics kk = c.intrinsics();
        if (kk.fx <= 0 || kk.fy <= 0)
            throw Error(in.file() + ": " + named + " has a focal length <= 0 in 'params'");
    }
    in.expect_end();
    return cameras;
}

std::vector<ColmapImage> read_images_binary(const fs::path& file) {
    const std::string bytes = read_whole_file(file);
    Cursor in(file, bytes);
    // The smallest image record: id, qvec, tvec, camera_id, a one-character name and its NUL, a point count.
    const uint64_t n = in.read_count("the image count", 4 + 4 * 8 + 3 * 8 + 4 + 2 + 8);
    std::vector<ColmapImage> images(n);
    for (uint64_t i = 0; i < n; ++i) {
        ColmapImage& im = images[i];
        im.id = in.read<int32_t>("image " + std::to_string(i) + ", field 'image_id'");
        const std::string rec = "image " + std::to_string(im.id);
        for (int k = 0; k < 4; ++k) im.qvec[size_t(k)] = in.read_finite(rec + ", field 'qvec'");
        for (int k = 0; k < 3; ++k) im.tvec[size_t(k)] = in.read_finite(rec + ", field 'tvec'");
        const double qn = im.qvec[0] * im.qvec[0] + im.qvec[1] * im.qvec[1] + im.qvec[2] * im.qvec[2] +
                          im.qvec[3] * im.qvec[3];
        if (qn < 1e-12) throw Error(in.file() + ": " + rec + " has a zero quaternion in 'qvec'");
        im.camera_id = in.read<int32_t>(rec + ", field 'camera_id'");
        im.name = in.read_cstring(rec + ", field 'name'");
        if (im.name.empty()) throw Error(in.file() + ": " + rec + " has an empty 'name'");
        const std::string named = rec + " ('" + im.name + "')";
        const uint64_t np = in.read_count(named + ", field 'num_points2D'", 3 * 8);
        im.points2d.resize(np);
        for (auto& p : im.points2d) {
            p.x = in.read_finite(named + ", field 'points2D'");
            p.y = in.read_finite(named + ", field 'points2D'");
            p.point3d_id = in.read<int64_t>(named + ", field 'points2D'");
        }
    }
    in.expect_end();
    return images;
}

std::vector<ColmapPoint3D> read_points3d_binary(const fs::path& file) {
    const std::string bytes = read_whole_file(file);
    Cursor in(file, bytes);
    // The smallest point record: id, xyz, rgb, error, an empty track's length.
    const uint64_t n = in.read_count("the point count", 8 + 3 * 8 + 3 + 8 + 8);
    std::vector<ColmapPoint3D> points(n);
    for (uint64_t i = 0; i < n; ++i) {
        ColmapPoint3D& p = points[i];
        p.id = in.read<uint64_t>("point " + std::to_string(i) + ", field 'point3D_id'");
        const std::string rec = "point " + std::to_string(p.id);
        for (auto& v : p.xyz) v = in.read_finite(rec + ", field 'xyz'");
        for (auto& v : p.rgb) v = in.read<uint8_t>(rec + ", field 'rgb'");
        p.error = in.read<double>(rec + ", field 'error'");  // COLMAP writes -1 for "unknown"; kept as is
        const uint64_t nt = in.read_count(rec + ", field 'track_length'", 2 * 4);
        p.track.resize(nt);
        for (auto& t : p.track) {
            t.image_id = in.read<int32_t>(rec + ", field 'track'");
            t.point2d_idx = in.read<int32_t>(rec + ", field 'track'");
        }
    }
    in.expect_end();
    return points;
}

ColmapModel read_colmap_model(const fs::path& folder) {
    ColmapModel model;
    model.cameras = read_cameras_binary(folder / "cameras.bin");
    model.images = read_images_binary(folder / "images.bin");
    model.points = read_points3d_binary(folder / "points3D.bin");

    const std::string images_file = (folder / "images.bin").string();
    const std::string points_file = (folder / "points3D.bin").string();
    for (const auto& im : model.images)
        if (!model.find_camera(im.camera_id))
            throw Error(images_file + ": image " + std::to_string(im.id) + " ('" + im.name +
                        "') uses camera " + std::to_string(im.camera_id) +
                        ", which cameras.bin does not have");
    std::unordered_map<int32_t, const ColmapImage*> by_id;
    for (const auto& im : model.images) by_id[im.id] = &im;
    for (const auto& p : model.points)
        for (size_t k = 0; k < p.track.size(); ++k) {
            const auto& t = p.track[k];
            const auto it = by_id.find(t.image_id);
            const std::string rec =
                points_file + ": point " + std::to_string(p.id) + ", track element " + std::to_string(k);
            if (it == by_id.end())
                throw Error(rec + " names image " + std::to_string(t.image_id) +
                            ", which images.bin does not have");
            if (t.point2d_idx < 0 || size_t(t.point2d_idx) >= it->second->points2d.size())
                throw Error(rec + " names 2D point " + std::to_string(t.point2d_idx) + " of image " +
                            std::to_string(t.image_id) + ", which has " +
                            std::to_string(it->second->points2d.size()));
        }
    return model;
}

Vec2d project(const ColmapCamera& camera, const ColmapImage& image, const Vec3d& world) {
    const Mat4 w2c = image.world_to_camera();
    double pc[3];
    for (int r = 0; r < 3; ++r)
        pc[r] = w2c.m[r][0] * world[0] + w2c.m[r][1] * world[1] + w2c.m[r][2] * world[2] + w2c.m[r][3];
    const double u = pc[0] / pc[2], v = pc[1] / pc[2];
    const Intrinsics k = camera.intrinsics();
    // COLMAP's distortion (OpenCV's model): radial k1 r^2 + k2 r^4, tangential p1, p2.
    const double r2 = u * u + v * v, uv = u * v;
    const double radial = k.k1 * r2 + k.k2 * r2 * r2;
    const double du = u * radial + 2 * k.p1 * uv + k.p2 * (r2 + 2 * u * u);
    const double dv = v * radial + 2 * k.p2 * uv + k.p1 * (r2 + 2 * v * v);
    return {k.fx * (u + du) + k.cx, k.fy * (v + dv) + k.cy};
}

ReprojectionStats reprojection_error(const ColmapModel& model) {
    std::unordered_map<int32_t, const ColmapImage*> images;
    for (const auto& im : model.images) images[im.id] = &im;
    ReprojectionStats s;
    double sum = 0;
    for (const auto& p : model.points)
        for (const auto& t : p.track) {
            const ColmapImage& im = *images.at(t.image_id);
            const Point2D& obs = im.points2d.at(size_t(t.point2d_idx));
            const Vec2d px = project(*model.find_camera(im.camera_id), im, p.xyz);
            const double e = std::hypot(px[0] - obs.x, px[1] - obs.y);
            sum += e;
            s.max_px = std::max(s.max_px, e);
            ++s.observations;
        }
    s.mean_px = s.observations ? sum / double(s.observations) : 0.0;
    return s;
}

}  // namespace npt::capture
