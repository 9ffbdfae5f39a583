#include "nerf/relight/relight_samples.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>

#include "core/error.h"
#include "core/rng.h"
#include "core/srgb.h"
#include "nerf/field_batch.h"
#include "nerf/relight/intrinsic_field.h"

namespace npt::nerf {

namespace {

constexpr float k_two_pi = 6.28318530717959f;
constexpr float k_golden = 0.6180339887498949f;
constexpr int k_window = 64;        // samples of one ray evaluated as one batch
constexpr int k_tries_per_point = 16;  // pixels drawn for a point before giving up on it

// What a model ray gathers: its transmittance and the radiance it collects (linear), marched like the
// renderer's NeRF rays (march_nerf), in windows of samples evaluated as one batch.
struct RayResult {
    float transmittance = 1.0f;
    Rgb radiance{0.0f};
};

class ModelMarcher {
  public:
    ModelMarcher(const NerfModel& model)
        : m_layout(model.layout()), m_params(model.params.data()), m_grid(model.occupancy.view()),
          m_march(model.march_params()) {}

    const NerfLayout& layout() const { return m_layout; }
    const float* params() const { return m_params; }

    RayResult composite(const Ray& ray, float jitter, bool with_color) {
        RayResult r;
        float log_t = 0.0f;
        auto flush = [&] {
            if (m_pos.empty()) return;
            field_forward(m_layout, m_params, m_pos.data(), m_dirs.data(), m_pos.size(), with_color, m_batch);
            for (size_t i = 0; i < m_pos.size() && log_t > k_log_stop; ++i) {
                const float tau = m_batch.sigma[i] * m_dt[i];
                if (!(tau > 0.0f)) continue;
                if (with_color) {
                    const Rgb c = m_batch.rgb[i];
                    const Rgb lin(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z));
                    r.radiance += lin * (std::exp(log_t) * -std::expm1(-tau));
                }
                log_t -= tau;
            }
            clear();
        };
        clear();
        march_ray_visit(m_march, m_grid, ray, jitter, [&](const MarchSample& s) {
            m_pos.push_back(s.position);
            m_dirs.push_back(ray.d);
            m_dt.push_back(s.dt);
            if (m_pos.size() >= size_t(k_window)) flush();
            return log_t > k_log_stop;
        });
        flush();
        r.transmittance = log_t > k_log_stop ? std::exp(log_t) : 0.0f;
        return r;
    }

    // The scattering event of a camera ray drawn from its volume weights with target optical depth tau:
    // false when the ray leaves the model before reaching it.
    bool event(const Ray& ray, float jitter, float tau_target, Vec3* position) {
        float tau = 0.0f;
        bool found = false;
        clear();
        auto flush = [&] {
            if (m_pos.empty() || found) return;
            field_forward(m_layout, m_params, m_pos.data(), nullptr, m_pos.size(), false, m_batch);
            for (size_t i = 0; i < m_pos.size(); ++i) {
                tau += m_batch.sigma[i] * m_dt[i];
                if (tau >= tau_target) {
                    *position = m_pos[i];
                    found = true;
                    break;
                }
            }
            clear();
        };
        march_ray_visit(m_march, m_grid, ray, jitter, [&](const MarchSample& s) {
            m_pos.push_back(s.position);
            m_dt.push_back(s.dt);
            if (m_pos.size() >= size_t(k_window)) flush();
            return !found;
        });
        flush();
        return found;
    }

    // -grad(log sigma) at p by central differences; zero when the density is flat there.
    Vec3 density_normal(Vec3 p, float h) {
        Vec3 pts[6];
        for (int a = 0; a < 3; ++a) {
            Vec3 e(0.0f);
            e[a] = h;
            pts[2 * a] = p + e;
            pts[2 * a + 1] = p - e;
        }
        field_forward(m_layout, m_params, pts, nullptr, 6, false, m_batch);
        Vec3 g;
        for (int a = 0; a < 3; ++a)
            g[a] = std::log(std::max(m_batch.sigma[2 * a], 1e-6f)) - std::log(std::max(m_batch.sigma[2 * a + 1], 1e-6f));
        const float len = length(g);
        return len > 0.0f ? -g / len : Vec3(0.0f);
    }

  private:
    static constexpr float k_log_stop = -9.2103404f;  // ln(1e-4), as the renderer
    void clear() {
        m_pos.clear();
        m_dirs.clear();
        m_dt.clear();
    }
    NerfLayout m_layout;
    const float* m_params;
    OccupancyGridView m_grid;
    MarchParams m_march;
    FieldBatch m_batch;
    std::vector<Vec3> m_pos, m_dirs;
    std::vector<float> m_dt;
};

}  // namespace

RelightSamples gather_relight_samples(const NerfModel& model, const Dataset& data,
                                      const RelightSampleSettings& settings, const RelightProgressFn& progress) {
    if (data.cameras.empty()) throw Error("the relight stage needs training images; the data set has none");
    if (settings.points < 1 || settings.directions < 1)
        throw Error("relight: points and directions must be at least 1");
    const size_t n_points = size_t(settings.points);
    const int K = settings.directions;
    const Mat4& w2m = model.world_to_model;
    const uint8_t min_alpha = uint8_t(std::lround(std::clamp(settings.min_alpha, 0.0f, 1.0f) * 255.0f));

    struct Point {
        bool ok = false;
        Vec3 position, wo, normal;
        Rgb target;
        uint32_t image = 0;
    };
    std::vector<Point> points(n_points);
    std::vector<Vec3> dirs(n_points * K);
    std::vector<float> vis(n_points * K);
    std::vector<Rgb> ind(n_points * K);
    std::atomic<size_t> done{0};
    std::mutex progress_mutex;

    tbb::parallel_for(tbb::blocked_range<size_t>(0, n_points, 16), [&](const tbb::blocked_range<size_t>& range) {
        ModelMarcher marcher(model);
        for (size_t s = range.begin(); s != range.end(); ++s) {
            Pcg32 rng(mix64(settings.seed ^ 0x72656c69676874ULL), s);
            Point& pt = points[s];
            for (int attempt = 0; attempt < k_tries_per_point && !pt.ok; ++attempt) {
                const uint32_t img = rng.next_u32() % uint32_t(data.cameras.size());
                const float px = rng.next_float() * float(data.width);
                const float py = rng.next_float() * float(data.height);
                const float jitter = rng.next_float(), u_event = rng.next_float();
                const int ix = std::min(int(px), data.width - 1), iy = std::min(int(py), data.height - 1);
                const uint8_t* pix = data.image(img) + (size_t(iy) * data.width + ix) * 4;
                if (pix[3] < min_alpha) continue;
                const Ray world = generate_pixel_ray(data.cameras[img], px, py);
                const Ray mray{w2m.transform_point(world.o), normalize(w2m.transform_vector(world.d))};
                Vec3 x;
                if (!marcher.event(mray, jitter, -std::log1p(-std::min(u_event, 0.999999f)), &x)) continue;
                Vec3 n = marcher.density_normal(x, settings.normal_step);
                if (length(n) == 0.0f) continue;
                const Vec3 wo = -mray.d;
                if (dot(n, wo) < 0.0f) n = -n;
                pt.ok = true;
                pt.position = x;
                pt.wo = wo;
                pt.normal = n;
                pt.image = img;
                pt.target = Rgb(srgb_to_linear(pix[0] / 255.0f), srgb_to_linear(pix[1] / 255.0f),
                                srgb_to_linear(pix[2] / 255.0f));
            }
            if (pt.ok) {
                // Directions uniform over the hemisphere of n (equal-area rings on a spherical Fibonacci
                // lattice, turned by a random angle per point so that points do not share directions).
                const Frame frame = Frame::from_z(pt.normal);
                const float turn = rng.next_float();
                const Vec3 origin = pt.position + pt.normal * k_relit_event_offset;
                for (int k = 0; k < K; ++k) {
                    const float z = 1.0f - (float(k) + 0.5f) / float(K);
                    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
                    const float phi = k_two_pi * (float(k) * k_golden + turn);
                    const Vec3 d = normalize(frame.to_world(Vec3(r * std::cos(phi), r * std::sin(phi), z)));
                    const RayResult res = marcher.composite(Ray{origin, d}, rng.next_float(), true);
                    dirs[s * K + k] = d;
                    vis[s * K + k] = res.transmittance;
                    ind[s * K + k] = res.radiance;
                }
            }
            const size_t d = ++done;
            if (progress && (d % 256 == 0 || d == n_points)) {
                std::lock_guard<std::mutex> lock(progress_mutex);
                progress(d, n_points);
            }
        }
    });

    RelightSamples out;
    out.directions = K;
    for (size_t s = 0; s < n_points; ++s) {
        const Point& pt = points[s];
        if (!pt.ok) continue;
        out.position.push_back(pt.position);
        out.wo.push_back(pt.wo);
        out.normal.push_back(pt.normal);
        out.target.push_back(pt.target);
        out.image.push_back(pt.image);
        out.dir.insert(out.dir.end(), dirs.begin() + s * K, dirs.begin() + (s + 1) * K);
        out.visibility.insert(out.visibility.end(), vis.begin() + s * K, vis.begin() + (s + 1) * K);
        out.indirect.insert(out.indirect.end(), ind.begin() + s * K, ind.begin() + (s + 1) * K);
    }
    if (out.size() * 100 < n_points)
        throw Error("relight: only " + std::to_string(out.size()) + " of " + std::to_string(n_points) +
                    " training rays found the object (is the model trained, and do the images have alpha?)");
    return out;
}

}  // namespace npt::nerf
