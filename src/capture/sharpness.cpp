#include "capture/sharpness.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace npt::capture {

Grey to_grey(const Frame8& frame, int max_side) {
    const int longest = std::max(frame.width, frame.height);
    const int f = (max_side > 0 && longest > max_side) ? (longest + max_side - 1) / max_side : 1;
    Grey g;
    g.width = frame.width / f;
    g.height = frame.height / f;
    g.v.assign(size_t(g.width) * size_t(g.height), 0.0f);
    const float norm = 1.0f / float(f * f);
    for (int y = 0; y < g.height; ++y) {
        for (int x = 0; x < g.width; ++x) {
            float sum = 0.0f;
            for (int dy = 0; dy < f; ++dy) {
                for (int dx = 0; dx < f; ++dx) {
                    const uint8_t* p = frame.at(x * f + dx, y * f + dy);
                    sum += 0.299f * p[0] + 0.587f * p[1] + 0.114f * p[2];
                }
            }
            g.v[size_t(y) * size_t(g.width) + size_t(x)] = sum * norm;
        }
    }
    return g;
}

double laplacian_variance(const Grey& g) {
    if (g.width < 3 || g.height < 3) return 0.0;
    double sum = 0.0, sum2 = 0.0;
    for (int y = 1; y + 1 < g.height; ++y) {
        for (int x = 1; x + 1 < g.width; ++x) {
            const double l =
                double(g.at(x - 1, y)) + g.at(x + 1, y) + g.at(x, y - 1) + g.at(x, y + 1) - 4.0 * g.at(x, y);
            sum += l;
            sum2 += l * l;
        }
    }
    const double n = double(g.width - 2) * double(g.height - 2);
    const double mean = sum / n;
    return std::max(0.0, sum2 / n - mean * mean);
}

Selection select_sharp(const std::vector<double>& scores, const std::vector<bool>& candidate,
                       SharpnessRule rule, int target) {
    if (target <= 0) throw Error(fmt::format("curate: --target-frames must be at least 1 (got {})", target));
    if (candidate.size() != scores.size()) throw Error("curate: candidate and score counts differ");
    const size_t n = scores.size();
    Selection s;
    s.kept.assign(n, false);
    s.reason.assign(n, "");
    if (n == 0) return s;
    double sum = 0.0, sum2 = 0.0;
    for (double v : scores) {
        sum += v;
        sum2 += v * v;
    }
    s.mean = sum / double(n);
    s.stddev = std::sqrt(std::max(0.0, sum2 / double(n) - s.mean * s.mean));

    if (rule == SharpnessRule::Threshold) {
        const double cut = s.mean - s.stddev;
        for (size_t i = 0; i < n; ++i) {
            if (!candidate[i]) continue;
            s.kept[i] = scores[i] >= cut;
            if (!s.kept[i])
                s.reason[i] =
                    fmt::format("blurry: sharpness {:.1f} below mean - 1 sigma ({:.1f})", scores[i], cut);
        }
        return s;
    }
    const double cut = s.mean - 2.0 * s.stddev;
    // Window w holds frames [w n / target, (w + 1) n / target): equal spans of time, because frames are
    // decoded at a constant step.
    const size_t windows = std::min(n, size_t(target));
    for (size_t w = 0; w < windows; ++w) {
        const size_t begin = w * n / windows, end = (w + 1) * n / windows;
        size_t best = end;
        for (size_t i = begin; i < end; ++i) {
            if (candidate[i] && (best == end || scores[i] > scores[best])) best = i;
        }
        for (size_t i = begin; i < end; ++i) {
            if (candidate[i] && i != best) s.reason[i] = fmt::format("not the sharpest of window {}", w);
        }
        if (best == end) continue;
        if (scores[best] < cut) {
            s.reason[best] =
                fmt::format("blurry: sharpest of window {} but {:.1f} is below mean - 2 sigma ({:.1f})", w,
                            scores[best], cut);
        } else {
            s.kept[best] = true;
        }
    }
    return s;
}

}  // namespace npt::capture
