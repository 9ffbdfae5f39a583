// Host builder of the piecewise-constant 2D distribution: per-row conditional CDFs and the marginal CDF over
// rows, accumulated in double so that large environment maps do not lose small texels to rounding.
#include "core/distribution_2d.h"

#include <cmath>

#include "core/error.h"

namespace npt {

namespace {

// Writes the normalised CDF of `w` (n entries) into cdf[0..n]; returns the plain sum. An all-zero row gets a
// uniform CDF so that its conditional is still a valid distribution (it is never chosen by the marginal).
double build_cdf(const double* w, int n, float* cdf) {
    double sum = 0.0;
    for (int i = 0; i < n; ++i) sum += w[i];
    double acc = 0.0;
    cdf[0] = 0.0f;
    for (int i = 0; i < n; ++i) {
        acc += sum > 0.0 ? w[i] : 1.0;
        cdf[i + 1] = float(acc / (sum > 0.0 ? sum : double(n)));
    }
    cdf[n] = 1.0f;
    return sum;
}

}  // namespace

Distribution2D::Distribution2D(const std::vector<float>& func, int nu, int nv) {
    if (nu <= 0 || nv <= 0 || size_t(nu) * size_t(nv) != func.size())
        throw Error("distribution 2d: weights do not match the " + std::to_string(nu) + " x " +
                    std::to_string(nv) + " grid");
    for (float f : func)
        if (!std::isfinite(f) || f < 0.0f) throw Error("distribution 2d: weight is negative or not finite");
    m_func = func;
    m_nu = nu;
    m_nv = nv;
    m_conditional.assign(size_t(nv) * size_t(nu + 1), 0.0f);
    m_marginal_cdf.assign(size_t(nv) + 1, 0.0f);
    std::vector<double> row(static_cast<size_t>(nu)), row_sums(static_cast<size_t>(nv));
    for (int v = 0; v < nv; ++v) {
        for (int u = 0; u < nu; ++u) row[size_t(u)] = double(func[size_t(v) * size_t(nu) + size_t(u)]);
        row_sums[size_t(v)] = build_cdf(row.data(), nu, m_conditional.data() + size_t(v) * size_t(nu + 1));
    }
    double total = build_cdf(row_sums.data(), nv, m_marginal_cdf.data());
    // Each cell has area 1 / (nu nv), so the integral is the mean weight.
    m_integral = float(total / (double(nu) * double(nv)));
}

Distribution2DView Distribution2D::view() const {
    Distribution2DView v;
    v.func = {m_func.data(), m_func.size()};
    v.conditional = {m_conditional.data(), m_conditional.size()};
    v.marginal_cdf = {m_marginal_cdf.data(), m_marginal_cdf.size()};
    v.nu = m_nu;
    v.nv = m_nv;
    v.integral = m_integral;
    return v;
}

}  // namespace npt
