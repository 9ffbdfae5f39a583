#include "core/mask_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.h"
#include "core/image_io.h"

namespace npt {

namespace {

std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

template <typename A, typename B>
void check_same_size(const A& a, const B& b, const char* what) {
    if (a.width != b.width || a.height != b.height)
        throw Error(std::string(what) + ": mask sizes differ (" + size_text(a.width, a.height) + " vs " +
                    size_text(b.width, b.height) + ")");
}

size_t pixel_count(int w, int h) { return size_t(std::max(w, 0)) * size_t(std::max(h, 0)); }

// Felzenszwalb & Huttenlocher's 1D squared distance transform of the lower envelope of parabolas rooted at
// the finite samples of f (stride apart in memory); samples with no finite value anywhere stay infinite. Only
// finite samples enter the envelope, so no "large number" stands in for infinity and loses precision.
void distance_1d(double* f, int n, size_t stride, std::vector<int>& v, std::vector<double>& z,
                 std::vector<double>& out) {
    const double inf = std::numeric_limits<double>::infinity();
    int k = -1;
    for (int q = 0; q < n; ++q) {
        const double fq = f[size_t(q) * stride];
        if (!std::isfinite(fq)) continue;
        double s = -inf;
        while (k >= 0) {
            const int p = v[size_t(k)];
            const double fp = f[size_t(p) * stride];
            s = ((fq + double(q) * q) - (fp + double(p) * p)) / (2.0 * (q - p));
            if (s > z[size_t(k)]) break;
            --k;
        }
        if (k < 0) s = -inf;
        ++k;
        v[size_t(k)] = q;
        z[size_t(k)] = s;
    }
    if (k < 0) return;  // no finite sample: all stay infinite
    int j = 0;
    for (int q = 0; q < n; ++q) {
        while (j < k && z[size_t(j) + 1] < q) ++j;
        const int p = v[size_t(j)];
        out[size_t(q)] = double(q - p) * double(q - p) + f[size_t(p) * stride];
    }
    for (int q = 0; q < n; ++q) f[size_t(q) * stride] = out[size_t(q)];
}

// Squared Euclidean distance from each pixel to the nearest set pixel (infinite when none is set).
std::vector<double> squared_distance(const Mask& mask) {
    const int w = mask.width, h = mask.height;
    const double inf = std::numeric_limits<double>::infinity();
    std::vector<double> d(pixel_count(w, h));
    for (size_t i = 0; i < d.size(); ++i) d[i] = mask.on[i] ? 0.0 : inf;
    const int n = std::max(w, h);
    std::vector<int> v(size_t(n) + 1);
    std::vector<double> z(size_t(n) + 1), out(size_t(n) + 1);
    for (int x = 0; x < w; ++x) distance_1d(d.data() + x, h, size_t(w), v, z, out);
    for (int y = 0; y < h; ++y) distance_1d(d.data() + size_t(y) * size_t(w), w, 1, v, z, out);
    return d;
}

void check_mask(const Mask& m, const char* what) {
    if (m.width < 0 || m.height < 0 || m.on.size() != pixel_count(m.width, m.height))
        throw Error(std::string(what) + ": mask buffer does not match its size " +
                    size_text(m.width, m.height));
}

// The mean predicted coverage, clamped to [0, 1] (NaN as 0), over the pixels where mask.on[i] == on; `empty`
// when there are none.
double mean_coverage_where(const Coverage& predicted, const Mask& mask, uint8_t on, double empty) {
    double sum = 0;
    size_t count = 0;
    for (size_t i = 0; i < mask.on.size(); ++i) {
        if (mask.on[i] != on) continue;
        const float a = predicted.values[i];
        sum += std::isfinite(a) ? std::clamp(double(a), 0.0, 1.0) : 0.0;
        ++count;
    }
    return count == 0 ? empty : sum / double(count);
}

}  // namespace

Mask threshold_coverage(const Coverage& coverage, float threshold) {
    Mask m{coverage.width, coverage.height, std::vector<uint8_t>(coverage.values.size())};
    for (size_t i = 0; i < coverage.values.size(); ++i) m.on[i] = coverage.values[i] > threshold ? 1 : 0;
    return m;
}

double mask_iou(const Mask& a, const Mask& b) {
    check_same_size(a, b, "mask IoU");
    size_t both = 0, any = 0;
    for (size_t i = 0; i < a.on.size(); ++i) {
        both += size_t(a.on[i] && b.on[i]);
        any += size_t(a.on[i] || b.on[i]);
    }
    return any == 0 ? 1.0 : double(both) / double(any);
}

Mask mask_boundary(const Mask& mask) {
    check_mask(mask, "mask boundary");
    const int w = mask.width, h = mask.height;
    Mask b{w, h, std::vector<uint8_t>(mask.on.size(), 0)};
    const auto at = [&](int x, int y) { return mask.on[size_t(y) * size_t(w) + size_t(x)]; };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const uint8_t s = at(x, y);
            bool edge = false;
            if (x + 1 < w && y + 1 < h)
                edge = s != at(x + 1, y) || s != at(x, y + 1) || s != at(x + 1, y + 1);
            else if (x + 1 < w)  // last row
                edge = s != at(x + 1, y);
            else if (y + 1 < h)  // last column
                edge = s != at(x, y + 1);
            b.on[size_t(y) * size_t(w) + size_t(x)] = edge ? 1 : 0;
        }
    return b;
}

Mask dilate_mask(const Mask& mask, double radius) {
    check_mask(mask, "mask dilation");
    const std::vector<double> d = squared_distance(mask);
    const double r2 = radius * radius;
    Mask out{mask.width, mask.height, std::vector<uint8_t>(d.size())};
    for (size_t i = 0; i < d.size(); ++i) out.on[i] = d[i] <= r2 ? 1 : 0;
    return out;
}

int boundary_tolerance(int width, int height) {
    return int(std::ceil(0.008 * std::hypot(double(width), double(height))));
}

BoundaryScore boundary_f(const Mask& predicted, const Mask& truth, int tolerance) {
    check_same_size(predicted, truth, "boundary F");
    const Mask pb = mask_boundary(predicted), tb = mask_boundary(truth);
    const Mask pd = dilate_mask(pb, tolerance), td = dilate_mask(tb, tolerance);
    size_t n_pred = 0, n_truth = 0, pred_hit = 0, truth_hit = 0;
    for (size_t i = 0; i < pb.on.size(); ++i) {
        n_pred += pb.on[i];
        n_truth += tb.on[i];
        pred_hit += size_t(pb.on[i] && td.on[i]);
        truth_hit += size_t(tb.on[i] && pd.on[i]);
    }
    BoundaryScore s;
    if (n_pred == 0 && n_truth == 0) {
        s.precision = s.recall = 1.0;
    } else if (n_pred == 0) {
        s.precision = 1.0;
        s.recall = 0.0;
    } else if (n_truth == 0) {
        s.precision = 0.0;
        s.recall = 1.0;
    } else {
        s.precision = double(pred_hit) / double(n_pred);
        s.recall = double(truth_hit) / double(n_truth);
    }
    const double sum = s.precision + s.recall;
    s.f = sum > 0 ? 2.0 * s.precision * s.recall / sum : 0.0;
    return s;
}

double mask_leak(const Coverage& predicted, const Mask& truth, int margin) {
    check_same_size(predicted, truth, "mask leak");
    return mean_coverage_where(predicted, dilate_mask(truth, margin), 0, 0.0);
}

double mask_coverage_inside(const Coverage& predicted, const Mask& truth) {
    check_same_size(predicted, truth, "mask coverage");
    return mean_coverage_where(predicted, truth, 1, std::numeric_limits<double>::quiet_NaN());
}

MaskScores score_mask(const Coverage& predicted, const Mask& truth) {
    check_same_size(predicted, truth, "mask scores");
    const Mask p = threshold_coverage(predicted);
    MaskScores s;
    s.iou = mask_iou(p, truth);
    s.boundary = boundary_f(p, truth, boundary_tolerance(truth.width, truth.height));
    s.leak = mask_leak(predicted, truth);
    return s;
}

Coverage read_coverage(const std::filesystem::path& path) {
    const Image img = read_image(path, /*srgb=*/false);
    Coverage c{img.width, img.height, std::vector<float>(pixel_count(img.width, img.height))};
    const size_t ch = size_t(img.channels);
    bool use_alpha = false;
    if (img.channels == 4)  // an alpha channel that is opaque everywhere says nothing: the mask is in grey
        for (size_t i = 0; i < c.values.size() && !use_alpha; ++i) use_alpha = img.pixels[i * ch + 3] < 1.0f;
    for (size_t i = 0; i < c.values.size(); ++i) {
        const float* p = &img.pixels[i * ch];
        c.values[i] = use_alpha ? p[3] : (p[0] + p[1] + p[2]) / 3.0f;
    }
    return c;
}

Coverage downscale_coverage(const Coverage& coverage, int factor) {
    if (factor < 1 || factor > coverage.width || factor > coverage.height)
        throw Error("mask downscale: factor " + std::to_string(factor) + " does not fit a " +
                    size_text(coverage.width, coverage.height) + " mask");
    const int w = coverage.width / factor, h = coverage.height / factor;
    Coverage out{w, h, std::vector<float>(pixel_count(w, h))};
    const double norm = 1.0 / (double(factor) * double(factor));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double sum = 0;
            for (int dy = 0; dy < factor; ++dy)
                for (int dx = 0; dx < factor; ++dx)
                    sum += coverage.values[size_t(y * factor + dy) * size_t(coverage.width) +
                                           size_t(x * factor + dx)];
            out.values[size_t(y) * size_t(w) + size_t(x)] = float(sum * norm);
        }
    return out;
}

double psnr_inside(const Image& a, const Image& b, const Mask& mask) {
    if (a.width != b.width || a.height != b.height || a.width != mask.width || a.height != mask.height ||
        a.channels < 3 || b.channels < 3)
        throw Error("PSNR inside the mask: the render, the truth and the mask differ in size");
    double sum = 0;
    size_t n = 0;
    for (size_t p = 0; p < mask.on.size(); ++p) {
        if (!mask.on[p]) continue;
        for (int c = 0; c < 3; ++c) {
            const double d = double(a.pixels[p * a.channels + c]) - b.pixels[p * b.channels + c];
            sum += d * d;
        }
        ++n;
    }
    if (n == 0) throw Error("PSNR inside the mask: the mask covers no pixel");
    const double mse = sum / (3.0 * double(n));
    return mse == 0 ? std::numeric_limits<double>::infinity() : -10.0 * std::log10(mse);
}

}  // namespace npt
