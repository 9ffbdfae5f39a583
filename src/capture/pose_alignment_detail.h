// Pieces of pose_alignment.cpp that pose_time_mapping.cpp shares: the non-throwing Umeyama fit (the search
// tries thousands of candidates, some degenerate), the median, and locating a time between sorted frames.
#pragma once

#include <optional>
#include <vector>

#include "capture/pose_alignment.h"

namespace npt::capture::detail {

// Partially reorders v. v must not be empty.
double median(std::vector<double>& v);

// fit_similarity without the exceptions: nullopt where it would throw.
std::optional<Similarity> try_fit_similarity(const std::vector<Eigen::Vector3d>& from,
                                             const std::vector<Eigen::Vector3d>& to);

// RMS distance of the points from their mean.
double trajectory_scale(const std::vector<Eigen::Vector3d>& centres);

// Frame times, sorted once, to interpolate at any time in their span.
class TimedTrack {
  public:
    // Throws npt::Error when a time is not finite or two are equal.
    explicit TimedTrack(const std::vector<double>& times);

    struct Bracket {
        size_t i0, i1;  // indices into the times as given
        double u;       // weight of i1: the time is (1 - u) t[i0] + u t[i1]
    };
    // nullopt outside [first, last].
    std::optional<Bracket> locate(double t) const;

    double first() const { return m_sorted.front(); }
    double last() const { return m_sorted.back(); }

  private:
    std::vector<double> m_sorted;
    std::vector<size_t> m_order;  // m_sorted[k] = times[m_order[k]]
};

}  // namespace npt::capture::detail
