// fit_time_mapping: the (a, b) of "reference frame i = video frame a i + b" by grid search. Each candidate
// interpolates only the estimate's centres and scores the median aligned centre error; the full matching and
// comparison run once, for the winner.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "capture/pose_alignment.h"
#include "capture/pose_alignment_detail.h"
#include "core/error.h"

namespace npt::capture {

namespace detail {

TimedTrack::TimedTrack(const std::vector<double>& times) : m_order(times.size()) {
    if (times.size() < 2)
        throw Error("time matching: needs at least 2 estimate poses to interpolate between");
    std::iota(m_order.begin(), m_order.end(), size_t(0));
    std::sort(m_order.begin(), m_order.end(), [&](size_t a, size_t b) { return times[a] < times[b]; });
    for (size_t k : m_order) {
        if (!std::isfinite(times[k]))
            throw Error("time matching: the time of estimate pose " + std::to_string(k) + " is not finite");
        if (!m_sorted.empty() && m_sorted.back() == times[k])
            throw Error("time matching: two estimate poses at time " + std::to_string(times[k]));
        m_sorted.push_back(times[k]);
    }
}

std::optional<TimedTrack::Bracket> TimedTrack::locate(double t) const {
    if (!(t >= m_sorted.front() && t <= m_sorted.back())) return std::nullopt;
    // First frame after t; t == last belongs to the last interval.
    size_t k1 = size_t(std::upper_bound(m_sorted.begin(), m_sorted.end(), t) - m_sorted.begin());
    k1 = std::min(std::max(k1, size_t(1)), m_sorted.size() - 1);
    const size_t k0 = k1 - 1;
    const double u = (t - m_sorted[k0]) / (m_sorted[k1] - m_sorted[k0]);
    return Bracket{m_order[k0], m_order[k1], u};
}

}  // namespace detail

namespace {

using Eigen::Vector3d;

constexpr double k_infinite = std::numeric_limits<double>::infinity();

struct Candidate {
    double a = 0, b = 0, score = k_infinite;
};

// Everything a candidate's score needs, prepared once.
struct Problem {
    const std::vector<CameraPose>& estimate;
    const std::vector<CameraPose>& reference;
    detail::TimedTrack track;
    size_t min_matched;

    // Median aligned centre error over the trajectory scale; infinite when too few match or the fit fails.
    double score(double a, double b) const {
        std::vector<Vector3d> from, to;
        for (size_t i = 0; i < reference.size(); ++i) {
            const auto at = track.locate(a * double(i) + b);
            if (!at) continue;
            from.push_back((1 - at->u) * estimate[at->i0].centre + at->u * estimate[at->i1].centre);
            to.push_back(reference[i].centre);
        }
        if (from.size() < min_matched) return k_infinite;
        const auto sim = detail::try_fit_similarity(from, to);
        if (!sim) return k_infinite;
        const double scale = detail::trajectory_scale(to);
        if (!(scale > 0)) return k_infinite;
        std::vector<double> errors;
        for (size_t i = 0; i < from.size(); ++i) errors.push_back((sim->apply(from[i]) - to[i]).norm());
        return detail::median(errors) / scale;
    }

    // How many reference frames a i + b puts inside the estimate's span, without matching anything.
    size_t inside(double a, double b) const {
        const double lo = std::ceil((track.first() - b) / a), hi = std::floor((track.last() - b) / a);
        const double n = std::min(hi, double(reference.size()) - 1) - std::max(lo, 0.0) + 1;
        return n > 0 ? size_t(n) : 0;
    }
};

// The best candidate over a grid: a_values times b in [b_lo, b_hi] with step b_step, parallel over a.
Candidate search(const Problem& p, const std::vector<double>& a_values, auto b_range, double b_step) {
    std::vector<Candidate> best(a_values.size());
    tbb::parallel_for(size_t(0), a_values.size(), [&](size_t k) {
        const double a = a_values[k];
        const auto [b_lo, b_hi] = b_range(a);
        for (double b = b_lo; b <= b_hi + 1e-9 * b_step; b += b_step) {
            if (p.inside(a, b) < p.min_matched) continue;
            const double s = p.score(a, b);
            if (s < best[k].score) best[k] = {a, b, s};
        }
    });
    Candidate out;
    for (const Candidate& c : best)
        if (c.score < out.score) out = c;
    return out;
}

}  // namespace

TimeMapping fit_time_mapping(const std::vector<CameraPose>& estimate,
                             const std::vector<double>& estimate_frames,
                             const std::vector<CameraPose>& reference, const TimeMappingSettings& settings) {
    if (estimate.size() != estimate_frames.size())
        throw Error("time mapping: " + std::to_string(estimate.size()) + " estimated poses but " +
                    std::to_string(estimate_frames.size()) + " frame numbers");
    if (!(settings.a_min > 0 && settings.a_max >= settings.a_min))
        throw Error("time mapping: the range of a must satisfy 0 < a_min <= a_max");
    const size_t min_matched =
        std::max(size_t(3), size_t(std::ceil(settings.min_matched_fraction * double(reference.size()))));
    if (reference.size() < 3) throw Error("time mapping: needs at least 3 reference poses");
    const Problem p{estimate, reference, detail::TimedTrack(estimate_frames), min_matched};

    // Coarse: a in 1% steps, b in 1/200 of the span over every offset that can overlap the estimate. A 1%
    // error in a or a half step in b moves the reference's far end by under 1% of the span, well inside the
    // basin of any camera path that does not repeat itself faster than that.
    const double span = p.track.last() - p.track.first();
    std::vector<double> a_values;
    for (double a = settings.a_min; a <= settings.a_max * (1 + 1e-12); a *= 1.01) a_values.push_back(a);
    const double n = double(reference.size());
    double b_step = span / 200;
    Candidate best = search(
        p, a_values, [&](double a) { return std::pair(p.track.first() - a * (n - 1), p.track.last()); },
        b_step);
    if (!(best.score < k_infinite))
        throw Error("time mapping: no a in [" + std::to_string(settings.a_min) + ", " +
                    std::to_string(settings.a_max) + "] puts " + std::to_string(min_matched) + " of the " +
                    std::to_string(reference.size()) + " reference frames inside the estimate's frames " +
                    std::to_string(p.track.first()) + ".." + std::to_string(p.track.last()) +
                    " with a sound alignment");

    // Two finer grids around the best, each with a tenth of the previous step and 3 previous steps either
    // way: the basin is a diagonal valley (a slightly larger a with a smaller b shifts the middle frames
    // alike), so the coarse best can sit a step or two off the true (a, b) in both.
    double a_rel = 0.01;
    for (int round = 0; round < 2; ++round) {
        a_values.clear();
        for (int k = -30; k <= 30; ++k) a_values.push_back(best.a * (1 + a_rel * k / 10.0));
        const double b0 = best.b, reach = 3 * b_step;
        const Candidate c = search(
            p, a_values, [&](double) { return std::pair(b0 - reach, b0 + reach); }, b_step / 10);
        if (c.score < best.score) best = c;
        a_rel /= 10;
        b_step /= 10;
    }

    TimeMapping out;
    out.a = best.a;
    out.b = best.b;
    std::vector<double> reference_times;
    for (size_t i = 0; i < reference.size(); ++i) reference_times.push_back(best.a * double(i) + best.b);
    out.matched = match_by_time(estimate, estimate_frames, reference, reference_times);
    out.comparison = compare_poses(out.matched.estimate, out.matched.reference);
    return out;
}

}  // namespace npt::capture
