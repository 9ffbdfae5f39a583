// Piecewise-constant 2D distribution over [0,1)^2 (marginal over rows v, conditional over columns u), used to
// importance-sample environment maps. The host builds owned arrays; Distribution2DView samples on CPU and
// GPU.
#pragma once

#include <vector>

#include "core/platform.h"
#include "core/vec.h"

namespace npt {

// Largest i in [0, n-1] with cdf[i] <= u, for a non-decreasing cdf of n+1 entries. Picking the largest such i
// skips zero-width (zero-probability) intervals, so a sample never lands in a cell whose weight is 0.
NPT_HD NPT_INLINE int find_interval(const float* cdf, int n, float u) {
    int lo = 0, hi = n;  // invariant: cdf[lo] <= u (or lo == 0), answer in [lo, hi)
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (cdf[mid] <= u)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

struct Distribution2DView {
    Span<const float> func;         // nv rows of nu cell weights, row-major, row 0 at v = 0
    Span<const float> conditional;  // nv rows of nu + 1 normalised CDF values (row's cdf[0] = 0, cdf[nu] = 1)
    Span<const float> marginal_cdf;  // nv + 1 normalised CDF values over rows
    int nu = 0;
    int nv = 0;
    float integral = 0.0f;  // integral of the piecewise-constant function over the unit square

    NPT_HD bool valid() const { return nu > 0 && nv > 0 && integral > 0.0f; }

    // Density on the unit square (integrates to 1) at p; 0 outside [0,1)^2 or for an empty distribution.
    NPT_HD float pdf(Vec2 p) const {
        if (!valid() || !(p.x >= 0.0f && p.x < 1.0f && p.y >= 0.0f && p.y < 1.0f)) return 0.0f;
        int iu = int(p.x * float(nu)), iv = int(p.y * float(nv));
        if (iu >= nu) iu = nu - 1;
        if (iv >= nv) iv = nv - 1;
        return func[size_t(iv) * size_t(nu) + size_t(iu)] / integral;
    }

    // Maps u in [0,1)^2 to a point in [0,1)^2 distributed with density pdf(); writes that density.
    NPT_HD Vec2 sample(Vec2 u, float* pdf_out) const {
        if (!valid()) {
            *pdf_out = 0.0f;
            return {0.0f, 0.0f};
        }
        int iv = find_interval(marginal_cdf.data, nv, u.y);
        float c0 = marginal_cdf[size_t(iv)], c1 = marginal_cdf[size_t(iv) + 1];
        float dv = c1 > c0 ? (u.y - c0) / (c1 - c0) : 0.0f;
        const float* row = conditional.data + size_t(iv) * size_t(nu + 1);
        int iu = find_interval(row, nu, u.x);
        float r0 = row[iu], r1 = row[iu + 1];
        float du = r1 > r0 ? (u.x - r0) / (r1 - r0) : 0.0f;
        // Rounding may put the offset at 1; keep the point inside the chosen cell so pdf() agrees.
        const float k_below_one = 0.99999994f;
        du = clampf(du, 0.0f, k_below_one);
        dv = clampf(dv, 0.0f, k_below_one);
        Vec2 p{fminf((float(iu) + du) / float(nu), k_below_one),
               fminf((float(iv) + dv) / float(nv), k_below_one)};
        // Report the density of the cell we chose, not a re-lookup, so a point on a cell border cannot
        // disagree.
        *pdf_out = func[size_t(iv) * size_t(nu) + size_t(iu)] / integral;
        return p;
    }
};

class Distribution2D {
  public:
    Distribution2D() = default;
    // `func` holds nv rows of nu non-negative finite weights (row-major). Throws npt::Error on bad sizes or
    // values. All-zero weights give an invalid (empty) view whose pdf is 0 everywhere.
    Distribution2D(const std::vector<float>& func, int nu, int nv);
    Distribution2DView view() const;

  private:
    std::vector<float> m_func, m_conditional, m_marginal_cdf;
    int m_nu = 0, m_nv = 0;
    float m_integral = 0.0f;
};

}  // namespace npt
