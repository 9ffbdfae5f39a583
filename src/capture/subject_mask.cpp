#include "capture/subject_mask.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace npt::capture {
namespace {

float median_of(std::vector<float>& v) {
    if (v.empty()) return 0.0f;
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
    return v[v.size() / 2];
}

double median_of(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
    return v[v.size() / 2];
}

}  // namespace

bool HsvRange::contains(float h, float s, float v) const {
    const bool hue = h_min <= h_max ? (h >= h_min && h <= h_max) : (h >= h_min || h <= h_max);
    return hue && s >= s_min && s <= s_max && v >= v_min && v <= v_max;
}

void rgb_to_hsv(float r, float g, float b, float& h, float& s, float& v) {
    const float mx = std::max({r, g, b}), mn = std::min({r, g, b});
    const float d = mx - mn;
    v = mx;
    s = mx > 0.0f ? d / mx : 0.0f;
    if (d <= 0.0f) {
        h = 0.0f;
    } else if (mx == r) {
        h = 60.0f * std::fmod((g - b) / d + 6.0f, 6.0f);
    } else if (mx == g) {
        h = 60.0f * ((b - r) / d + 2.0f);
    } else {
        h = 60.0f * ((r - g) / d + 4.0f);
    }
}

HsvRange automatic_range(const Frame8& frame) {
    const double side = std::sqrt(0.1);
    const int w = std::max(1, int(frame.width * side)), h = std::max(1, int(frame.height * side));
    const int x0 = (frame.width - w) / 2, y0 = (frame.height - h) / 2;
    std::vector<float> hs, ss, vs;
    // Hue is circular: take the median of hues rotated so that the largest gap between them sits at 0,
    // otherwise a red object (hues near 0 and 360) would get a median of 180.
    std::vector<float> hist(360, 0.0f);
    for (int y = y0; y < y0 + h; ++y) {
        for (int x = x0; x < x0 + w; ++x) {
            const uint8_t* p = frame.at(x, y);
            float hh, s, v;
            rgb_to_hsv(p[0] / 255.0f, p[1] / 255.0f, p[2] / 255.0f, hh, s, v);
            hs.push_back(hh);
            ss.push_back(s);
            vs.push_back(v);
            hist[size_t(std::min(359, int(hh)))] += 1.0f;
        }
    }
    // Keep the more colourful half of the centre: floors, walls and tables around an object are usually
    // greyer than the object, and a centre square always catches some of them.
    std::vector<float> s_sorted = ss;
    const float s_half = median_of(s_sorted);
    std::vector<float> hs2, ss2, vs2;
    std::fill(hist.begin(), hist.end(), 0.0f);
    for (size_t i = 0; i < hs.size(); ++i) {
        if (ss[i] < s_half) continue;
        hs2.push_back(hs[i]);
        ss2.push_back(ss[i]);
        vs2.push_back(vs[i]);
        hist[size_t(std::min(359, int(hs[i])))] += 1.0f;
    }
    hs.swap(hs2);
    ss.swap(ss2);
    vs.swap(vs2);
    // Start of the longest run of empty hue bins: the cut where the circle is opened.
    int best_start = 0, best_len = 0;
    for (int start = 0; start < 360; ++start) {
        int len = 0;
        while (len < 360 && hist[size_t((start + len) % 360)] == 0.0f) ++len;
        if (len > best_len) {
            best_len = len;
            best_start = start;
        }
    }
    const float cut = float(best_start);
    for (float& hh : hs) hh = std::fmod(hh - cut + 360.0f, 360.0f);
    const float h_med = std::fmod(median_of(hs) + cut, 360.0f);
    const float s_med = median_of(ss), v_med = median_of(vs);
    HsvRange r;
    r.h_min = std::fmod(h_med - k_auto_hue_tolerance + 360.0f, 360.0f);
    r.h_max = std::fmod(h_med + k_auto_hue_tolerance, 360.0f);
    r.s_min = std::max(0.0f, s_med - k_auto_sv_tolerance);
    r.s_max = std::min(1.0f, s_med + k_auto_sv_tolerance);
    r.v_min = std::max(0.0f, v_med - k_auto_sv_tolerance);
    r.v_max = std::min(1.0f, v_med + k_auto_sv_tolerance);
    // A grey centre has no meaningful hue: accept any.
    if (s_med < 0.1f) {
        r.h_min = 0.0f;
        r.h_max = 360.0f;
    }
    return r;
}

void validate_range(const HsvRange& r) {
    auto check = [](const char* name, float lo, float hi, float limit) {
        if (!(lo >= 0.0f && hi <= limit)) {
            throw Error(fmt::format("curate: --hsv-min/--hsv-max: {} must lie in [0, {}] (got {}..{})", name,
                                    limit, lo, hi));
        }
        if (lo > hi) {
            throw Error(fmt::format("curate: --hsv-min {} ({}) is greater than --hsv-max {} ({})", name, lo,
                                    name, hi));
        }
    };
    check("H", r.h_min, r.h_max, 360.0f);
    check("S", r.s_min, r.s_max, 1.0f);
    check("V", r.v_min, r.v_max, 1.0f);
}

MaskResult subject_centroid(const Frame8& frame, const HsvRange& range, int max_side) {
    const int longest = std::max(frame.width, frame.height);
    const int f = (max_side > 0 && longest > max_side) ? (longest + max_side - 1) / max_side : 1;
    const int w = frame.width / f, h = frame.height / f;
    std::vector<uint8_t> mask(size_t(w) * size_t(h), 0);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            // Sample the block's centre pixel: thresholds need no averaging, and averages mix colours at
            // edges.
            const uint8_t* p = frame.at(x * f + f / 2, y * f + f / 2);
            float hh, s, v;
            rgb_to_hsv(p[0] / 255.0f, p[1] / 255.0f, p[2] / 255.0f, hh, s, v);
            mask[size_t(y) * size_t(w) + size_t(x)] = range.contains(hh, s, v) ? 1 : 0;
        }
    }
    MaskResult best;
    std::vector<int> stack;
    double best_sx = 0.0, best_sy = 0.0;
    for (int start = 0; start < w * h; ++start) {
        if (mask[size_t(start)] != 1) continue;
        mask[size_t(start)] = 2;
        stack.assign(1, start);
        int count = 0;
        double sx = 0.0, sy = 0.0;
        while (!stack.empty()) {
            const int i = stack.back();
            stack.pop_back();
            const int x = i % w, y = i / w;
            ++count;
            sx += x;
            sy += y;
            const int nb[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
            for (const auto& q : nb) {
                if (q[0] < 0 || q[1] < 0 || q[0] >= w || q[1] >= h) continue;
                const size_t j = size_t(q[1]) * size_t(w) + size_t(q[0]);
                if (mask[j] == 1) {
                    mask[j] = 2;
                    stack.push_back(int(j));
                }
            }
        }
        if (count > best.component_pixels) {
            best.component_pixels = count;
            best_sx = sx;
            best_sy = sy;
        }
    }
    if (best.component_pixels > 0) {
        // Centre of the block, in full-resolution pixel units (pixel centres at +0.5).
        best.centroid = Vec2(float((best_sx / best.component_pixels + 0.5) * f),
                             float((best_sy / best.component_pixels + 0.5) * f));
    }
    return best;
}

std::vector<std::string> centroid_outliers(const std::vector<std::optional<Vec2>>& centroids,
                                           double min_sigma, Vec2& centre, Vec2& sigma) {
    std::vector<double> xs, ys;
    for (const auto& c : centroids) {
        if (c) {
            xs.push_back(c->x);
            ys.push_back(c->y);
        }
    }
    const double mx = median_of(xs), my = median_of(ys);
    std::vector<double> dx, dy;
    for (size_t i = 0; i < xs.size(); ++i) {
        dx.push_back(std::abs(xs[i] - mx));
        dy.push_back(std::abs(ys[i] - my));
    }
    const double sx = std::max(min_sigma, 1.4826 * median_of(dx));
    const double sy = std::max(min_sigma, 1.4826 * median_of(dy));
    centre = Vec2(float(mx), float(my));
    sigma = Vec2(float(sx), float(sy));
    std::vector<std::string> reasons(centroids.size());
    for (size_t i = 0; i < centroids.size(); ++i) {
        const auto& c = centroids[i];
        if (!c) {
            reasons[i] = "no subject: the HSV mask is empty";
            continue;
        }
        const double zx = std::abs(c->x - mx) / sx, zy = std::abs(c->y - my) / sy;
        if (zx > k_centroid_sigmas || zy > k_centroid_sigmas) {
            reasons[i] = fmt::format(
                "subject off-centre: mask centroid ({:.0f}, {:.0f}) is {:.1f} sigma from ({:.0f}, {:.0f})",
                c->x, c->y, std::max(zx, zy), mx, my);
        }
    }
    return reasons;
}

}  // namespace npt::capture
