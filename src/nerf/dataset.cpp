// transforms.json reading: validates the whole json before touching an image (so a typo fails in
// milliseconds), then decodes the images in parallel straight into one RGBA buffer.
#include "nerf/dataset.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <sstream>

#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/memory.h"

namespace npt::nerf {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// What a frame's intrinsics need before its image is read: the focal length may come from an angle, which
// needs the image width, so it is resolved after loading.
struct FrameSpec {
    std::string file_path;
    Mat4 camera_to_world;
    std::optional<double> fl_x, fl_y, cx, cy, angle_x, angle_y;
    std::optional<int> w, h;
    float k1 = 0, k2 = 0, p1 = 0, p2 = 0;
    fs::path image;  // resolved on disk
};

std::string frame_label(size_t i, const std::string& file_path) {
    return "frame " + std::to_string(i) + " ('" + file_path + "')";
}

// A number from `obj`: absent -> nullopt; present but not a finite number -> error naming the field.
std::optional<double> opt_number(const json& obj, const char* key, const std::string& where) {
    auto it = obj.find(key);
    if (it == obj.end()) return std::nullopt;
    if (!it->is_number()) throw Error(where + ": '" + key + "' must be a number, got " + it->type_name());
    double v = it->get<double>();
    if (!std::isfinite(v)) throw Error(where + ": '" + key + "' is not finite (NaN or Inf)");
    return v;
}

// The frame's value if it has one, else the global one: both instant-ngp and nerfstudio allow either.
std::optional<double> frame_or_global(const json& frame, const json& root, const char* key,
                                      const std::string& frame_where, const std::string& file) {
    if (auto v = opt_number(frame, key, frame_where)) return v;
    return opt_number(root, key, file);
}

std::optional<int> opt_size(const json& frame, const json& root, const char* key,
                            const std::string& frame_where, const std::string& file) {
    auto v = frame_or_global(frame, root, key, frame_where, file);
    if (!v) return std::nullopt;
    if (*v < 1 || *v > k_max_image_side || *v != std::floor(*v))
        throw Error(frame_where + ": '" + key + "' must be a whole number of pixels in [1, " +
                    std::to_string(k_max_image_side) + "]");
    return int(*v);
}

Mat4 parse_matrix(const json& frame, const std::string& where) {
    auto it = frame.find("transform_matrix");
    if (it == frame.end()) throw Error(where + ": missing 'transform_matrix'");
    const json& m = *it;
    bool shape_ok = m.is_array() && m.size() == 4;
    for (size_t r = 0; shape_ok && r < 4; ++r) shape_ok = m[r].is_array() && m[r].size() == 4;
    if (!shape_ok) throw Error(where + ": 'transform_matrix' must be a 4x4 array of numbers");
    Mat4 out;
    for (size_t r = 0; r < 4; ++r)
        for (size_t c = 0; c < 4; ++c) {
            const json& v = m[r][c];
            // nlohmann writes NaN as null, so null here almost always was a NaN.
            if (v.is_null())
                throw Error(where + ": 'transform_matrix' has null (a NaN written as JSON) at row " +
                            std::to_string(r) + ", column " + std::to_string(c));
            if (!v.is_number()) throw Error(where + ": 'transform_matrix' must be a 4x4 array of numbers");
            double d = v.get<double>();
            if (!std::isfinite(d))
                throw Error(where + ": 'transform_matrix' has NaN or Inf at row " + std::to_string(r) +
                            ", column " + std::to_string(c));
            out.m[r][c] = d;
        }
    // A camera-to-world pose: affine (bottom row 0 0 0 1), with an invertible 3x3 part (columns of nonzero
    // length, not in one plane) and a position a float can hold. instant-ngp reads the matrix as it is.
    const double bottom =
        std::abs(out.m[3][0]) + std::abs(out.m[3][1]) + std::abs(out.m[3][2]) + std::abs(out.m[3][3] - 1.0);
    if (!(bottom <= 1e-6))
        throw Error(where + ": 'transform_matrix' is not a pose: its last row must be [0, 0, 0, 1]");
    double norms = 1;
    for (int c = 0; c < 3; ++c)
        norms *= std::sqrt(out.m[0][c] * out.m[0][c] + out.m[1][c] * out.m[1][c] + out.m[2][c] * out.m[2][c]);
    if (!(std::isfinite(norms) && std::abs(out.determinant3()) > 1e-6 * norms))
        throw Error(where + ": 'transform_matrix' is not invertible (its rotation part is zero or flat)");
    if (!is_finite(out.transform_point(Vec3(0.0f))))
        throw Error(where + ": 'transform_matrix' puts the camera beyond the range of a float");
    return out;
}

// The lens must be invertible over the whole image: every pixel is undistorted (Newton, as the ray generator
// does) and distorted back to within a hundredth of a pixel, on a 9x9 grid from corner to corner.
// Coefficients such as k1 = 1e30 fold the image over itself; the ray of such a pixel would be meaningless.
void check_lens(const Camera& c, const std::string& where) {
    const LensDistortion lens = c.distortion();
    if (lens.is_identity()) return;
    constexpr int k_grid = 9;
    for (int j = 0; j < k_grid; ++j)
        for (int i = 0; i < k_grid; ++i) {
            const double px = double(c.width) * i / (k_grid - 1), py = double(c.height) * j / (k_grid - 1);
            const double xd = (px - c.cx) / c.fx, yd = (py - c.cy) / c.fy;
            double x, y, xr, yr;
            undistort(lens, xd, yd, &x, &y);
            distort(lens, x, y, &xr, &yr);
            const double err = std::hypot((xr - xd) * c.fx, (yr - yd) * c.fy);
            if (!(err <= 0.01))
                throw Error(
                    fmt::format("{}: 'k1', 'k2', 'p1', 'p2' = {:g}, {:g}, {:g}, {:g} do not describe a lens "
                                "that can be inverted over the image (pixel ({:g}, {:g}) cannot be "
                                "undistorted)",
                                where, lens.k1, lens.k2, lens.p1, lens.p2, px, py));
        }
}

// `file_path` as given, then with the extensions exporters leave off (NeRF-synthetic writes "./train/r_0").
fs::path resolve_image(const fs::path& base_dir, const std::string& file_path, const std::string& where) {
    const fs::path given = base_dir / file_path;
    std::vector<fs::path> tried{given};
    for (const char* ext : {".png", ".jpg", ".jpeg"}) tried.push_back(fs::path(given.string() + ext));
    std::string list;
    for (const auto& p : tried) {
        std::error_code ec;
        if (fs::is_regular_file(p, ec)) return p;
        list += (list.empty() ? "" : ", ") + p.string();
    }
    throw Error(where + ": image not found (tried " + list + ")");
}

json read_json(const fs::path& path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw Error(path.string() + ": file not found");
    return read_json_file(path);
}

fs::path json_path(const fs::path& folder_or_json, const std::string& split) {
    std::error_code ec;
    if (!fs::is_directory(folder_or_json, ec)) return folder_or_json;
    const fs::path single = folder_or_json / "transforms.json";
    if (split.empty()) return single;
    const fs::path split_file = folder_or_json / ("transforms_" + split + ".json");
    // A capture (instant-ngp, nerfstudio, `nerfpt poses`) has one transforms.json and no splits: it is the
    // training set. Other splits never fall back, so evaluation cannot silently run on training views.
    if (split == "train" && !fs::exists(split_file, ec) && fs::exists(single, ec)) return single;
    return split_file;
}

}  // namespace

Dataset load_dataset(const fs::path& folder_or_json, const std::string& split, const ProgressFn& progress,
                     size_t max_frames) {
    const fs::path path = json_path(folder_or_json, split);
    const std::string file = path.string();
    const json root = read_json(path);
    if (!root.is_object()) throw Error(file + ": expected a JSON object at the top level");

    Dataset ds;
    ds.source = path;
    if (auto v = opt_number(root, "aabb_scale", file)) {
        // instant-ngp's limit (8 cascades); each cascade is a 128^3 occupancy grid.
        if (!(*v > 0 && *v <= k_max_aabb_scale))
            throw Error(file + ": 'aabb_scale' must be in (0, " + std::to_string(int(k_max_aabb_scale)) +
                        "], got " + json(*v).dump());
        ds.aabb_scale = float(*v);
    }
    if (auto v = opt_number(root, "scale", file)) {
        // Positions are multiplied by it: 0 puts every camera at one point, a negative value mirrors the
        // world.
        if (!(*v > 0) || !std::isfinite(float(*v)))
            throw Error(file + ": 'scale' must be a positive number, got " + json(*v).dump());
        ds.scale = float(*v);
    }
    if (auto it = root.find("offset"); it != root.end()) {
        if (!it->is_array() || it->size() != 3 || !(*it)[0].is_number() || !(*it)[1].is_number() ||
            !(*it)[2].is_number())
            throw Error(file + ": 'offset' must be an array of 3 numbers");
        ds.offset = Vec3((*it)[0].get<float>(), (*it)[1].get<float>(), (*it)[2].get<float>());
        if (!is_finite(ds.offset)) throw Error(file + ": 'offset' must be 3 finite numbers");
    }

    auto frames_it = root.find("frames");
    if (frames_it == root.end()) throw Error(file + ": missing 'frames'");
    if (!frames_it->is_array()) throw Error(file + ": 'frames' must be an array");
    if (frames_it->empty()) throw Error(file + ": 'frames' is empty");
    const size_t n_json = frames_it->size();

    const fs::path base_dir = path.parent_path();
    std::vector<FrameSpec> specs(n_json);
    for (size_t i = 0; i < n_json; ++i) {
        const json& fr = (*frames_it)[i];
        std::string where = file + ": frame " + std::to_string(i);
        if (!fr.is_object()) throw Error(where + ": expected an object");
        auto fp = fr.find("file_path");
        if (fp == fr.end() || !fp->is_string() || fp->get<std::string>().empty())
            throw Error(where + ": missing 'file_path' (a string)");
        FrameSpec& s = specs[i];
        s.file_path = fp->get<std::string>();
        where = file + ": " + frame_label(i, s.file_path);
        s.camera_to_world = parse_matrix(fr, where);
        s.fl_x = frame_or_global(fr, root, "fl_x", where, file);
        s.fl_y = frame_or_global(fr, root, "fl_y", where, file);
        s.cx = frame_or_global(fr, root, "cx", where, file);
        s.cy = frame_or_global(fr, root, "cy", where, file);
        s.angle_x = frame_or_global(fr, root, "camera_angle_x", where, file);
        s.angle_y = frame_or_global(fr, root, "camera_angle_y", where, file);
        if (!s.fl_x && !s.angle_x)
            throw Error(where + ": missing intrinsics: neither 'fl_x' nor 'camera_angle_x' is given");
        for (auto a : {s.angle_x, s.angle_y})
            if (a && (*a <= 0 || *a >= std::numbers::pi))
                throw Error(where + ": 'camera_angle_x'/'camera_angle_y' must be in (0, pi) radians");
        for (auto f : {s.fl_x, s.fl_y})
            if (f && *f <= 0) throw Error(where + ": 'fl_x'/'fl_y' must be positive");
        s.w = opt_size(fr, root, "w", where, file);
        s.h = opt_size(fr, root, "h", where, file);
        s.k1 = float(frame_or_global(fr, root, "k1", where, file).value_or(0.0));
        s.k2 = float(frame_or_global(fr, root, "k2", where, file).value_or(0.0));
        s.p1 = float(frame_or_global(fr, root, "p1", where, file).value_or(0.0));
        s.p2 = float(frame_or_global(fr, root, "p2", where, file).value_or(0.0));
        for (float k : {s.k1, s.k2, s.p1, s.p2})
            if (!std::isfinite(k)) throw Error(where + ": 'k1', 'k2', 'p1' and 'p2' must fit a float");
        s.image = resolve_image(base_dir, s.file_path, where);
    }
    if (max_frames > 0 && specs.size() > max_frames) {
        std::vector<FrameSpec> kept;
        for (size_t k = 0; k < max_frames; ++k) kept.push_back(specs[k * specs.size() / max_frames]);
        specs = std::move(kept);
    }
    const size_t n = specs.size();

    // The first image fixes the size, and with it the buffer, before the others are decoded in parallel.
    auto decode = [&](size_t i) {
        const std::string where = file + ": " + frame_label(i, specs[i].file_path);
        Image img;
        try {
            img = read_image(specs[i].image, /*srgb=*/false);  // keep the stored sRGB values
        } catch (const Error& e) {
            throw Error(where + ": " + e.what());
        }
        if (img.width <= 0 || img.height <= 0)
            throw Error(where + ": image " + specs[i].image.string() + " has no pixels");
        return img;
    };
    std::mutex progress_mutex;
    size_t done = 0;
    auto report = [&] {
        if (!progress) return;
        std::lock_guard lock(progress_mutex);
        progress(++done, n);
    };
    auto store = [&](size_t i, const Image& img) {
        const std::string where = file + ": " + frame_label(i, specs[i].file_path);
        if (img.width != ds.width || img.height != ds.height)
            throw Error(where + ": image " + specs[i].image.string() + " is " + std::to_string(img.width) +
                        "x" + std::to_string(img.height) + ", but the first frame's is " +
                        std::to_string(ds.width) + "x" + std::to_string(ds.height));
        uint8_t* dst = ds.rgba.data() + i * ds.image_bytes();
        const size_t count = size_t(img.width) * size_t(img.height);
        auto to_byte = [](float v) { return uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); };
        for (size_t p = 0; p < count; ++p) {
            const float* s = img.pixels.data() + p * size_t(img.channels);
            dst[4 * p + 0] = to_byte(s[0]);
            dst[4 * p + 1] = to_byte(s[1]);
            dst[4 * p + 2] = to_byte(s[2]);
            dst[4 * p + 3] = img.channels == 4 ? to_byte(s[3]) : 255;
        }
        report();
    };

    {
        Image first = decode(0);
        ds.width = first.width;
        ds.height = first.height;
        if (ds.image_bytes() > k_max_dataset_bytes / n)
            throw Error(file + ": " + std::to_string(n) + " frames of " + std::to_string(ds.width) + "x" +
                        std::to_string(ds.height) + " need more than the limit of " +
                        std::to_string(k_max_dataset_bytes >> 30) + " GiB of pixel memory");
        with_memory_context(file + ": " + std::to_string(n) + " frames of " + std::to_string(ds.width) + "x" +
                                std::to_string(ds.height),
                            double(n) * double(ds.image_bytes()),
                            "use fewer or smaller images (--downscale shrinks them only after loading)",
                            [&] { ds.rgba.resize(n * ds.image_bytes()); });
        store(0, first);
    }
    // Errors are kept per frame and the first is reported, so the message does not depend on thread timing.
    std::vector<std::string> errors(n);
    tbb::parallel_for(size_t(1), n, [&](size_t i) {
        try {
            store(i, decode(i));
        } catch (const Error& e) {
            errors[i] = e.what();
        }
    });
    for (const auto& e : errors)
        if (!e.empty()) throw Error(e);

    ds.cameras.resize(n);
    ds.names.resize(n);
    ds.image_files.resize(n);
    for (size_t i = 0; i < n; ++i) {
        const FrameSpec& s = specs[i];
        const std::string where = file + ": " + frame_label(i, s.file_path);
        if ((s.w && *s.w != ds.width) || (s.h && *s.h != ds.height))
            throw Error(where + ": 'w'/'h' say " + std::to_string(s.w.value_or(ds.width)) + "x" +
                        std::to_string(s.h.value_or(ds.height)) + " but the image is " +
                        std::to_string(ds.width) + "x" + std::to_string(ds.height));
        Camera& c = ds.cameras[i];
        c.camera_to_world = s.camera_to_world;
        c.width = ds.width;
        c.height = ds.height;
        const double fx = s.fl_x ? *s.fl_x : 0.5 * ds.width / std::tan(0.5 * *s.angle_x);
        // Without a vertical focal length or angle, pixels are square (instant-ngp does the same).
        const double fy = s.fl_y ? *s.fl_y : s.angle_y ? 0.5 * ds.height / std::tan(0.5 * *s.angle_y) : fx;
        c.fx = float(fx);
        c.fy = float(fy);
        c.cx = float(s.cx.value_or(0.5 * ds.width));
        c.cy = float(s.cy.value_or(0.5 * ds.height));
        c.k1 = s.k1;
        c.k2 = s.k2;
        c.p1 = s.p1;
        c.p2 = s.p2;
        if (!std::isfinite(c.fx) || !std::isfinite(c.fy) || !std::isfinite(c.cx) || !std::isfinite(c.cy) ||
            !(c.fx > 0) || !(c.fy > 0))
            throw Error(where + ": the intrinsics do not fit a float (fx " + json(fx).dump() + ", fy " +
                        json(fy).dump() + ")");
        check_lens(c, where);
        ds.names[i] = s.file_path;
        ds.image_files[i] = s.image;
    }
    spdlog::debug("{}: {} frames of {}x{}", file, n, ds.width, ds.height);
    return ds;
}

void downscale_dataset(Dataset& ds, int factor) {
    if (factor == 1) return;
    if (factor < 1 || factor > ds.width || factor > ds.height)
        throw Error("downscale factor " + std::to_string(factor) + " must be in 1.." +
                    std::to_string(std::min(ds.width, ds.height)) + " for " + std::to_string(ds.width) +
                    "x" + std::to_string(ds.height) + " images");
    const int w = ds.width / factor, h = ds.height / factor;
    const size_t n = ds.cameras.size();
    std::vector<uint8_t> out(n * size_t(w) * h * 4);
    tbb::parallel_for(size_t(0), n, [&](size_t i) {
        const uint8_t* src = ds.image(i);
        uint8_t* dst = out.data() + i * size_t(w) * h * 4;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                double acc[4] = {0, 0, 0, 0};
                for (int dy = 0; dy < factor; ++dy)
                    for (int dx = 0; dx < factor; ++dx) {
                        const uint8_t* p = src + (size_t(y * factor + dy) * ds.width + x * factor + dx) * 4;
                        const double a = p[3];
                        for (int c = 0; c < 3; ++c) acc[c] += p[c] * a;
                        acc[3] += a;
                    }
                uint8_t* q = dst + (size_t(y) * w + x) * 4;
                for (int c = 0; c < 3; ++c) q[c] = acc[3] > 0 ? uint8_t(std::lround(acc[c] / acc[3])) : 0;
                q[3] = uint8_t(std::lround(acc[3] / (factor * factor)));
            }
    });
    ds.rgba = std::move(out);
    ds.width = w;
    ds.height = h;
    for (Camera& c : ds.cameras) {
        c.fx /= float(factor);
        c.fy /= float(factor);
        c.cx /= float(factor);
        c.cy /= float(factor);
        c.width = w;
        c.height = h;
    }
}

Ray generate_pixel_ray(const Camera& camera, float px, float py) {
    // Normalised coordinates with y down (OpenCV's, where the distortion model lives), flipped to OpenGL's
    // y up for the direction. -(a / b) rounds exactly as (-a) / b did: the zero-distortion ray is unchanged.
    float x = (px - camera.cx) / camera.fx, y = (py - camera.cy) / camera.fy;
    const LensDistortion lens = camera.distortion();
    if (!lens.is_identity()) undistort(lens, x, y, &x, &y);
    const Vec3 d_cam(x, -y, -1.0f);
    const Vec3 d = camera.camera_to_world.transform_vector(d_cam);
    return Ray{camera.camera_to_world.transform_point(Vec3(0.0f, 0.0f, 0.0f)), normalize(d)};
}

}  // namespace npt::nerf
