#include "core/alias_table.h"

#include <cmath>

#include "core/error.h"

namespace npt {

AliasTable::AliasTable(const std::vector<double>& weights) {
    double total = 0.0;
    for (double w : weights) {
        if (!std::isfinite(w) || w < 0.0) throw Error("alias table: weight is negative or not finite");
        total += w;
    }
    if (weights.empty() || total <= 0.0) return;

    size_t n = weights.size();
    m_bins.resize(n);
    std::vector<double> scaled(n);
    std::vector<uint32_t> small, large;
    for (size_t i = 0; i < n; ++i) {
        m_bins[i].pmf = float(weights[i] / total);
        scaled[i] = weights[i] / total * double(n);
        (scaled[i] < 1.0 ? small : large).push_back(uint32_t(i));
    }
    while (!small.empty() && !large.empty()) {
        uint32_t s = small.back(), l = large.back();
        small.pop_back();
        m_bins[s].q = float(scaled[s]);
        m_bins[s].alias = l;
        scaled[l] -= 1.0 - scaled[s];
        if (scaled[l] < 1.0) {
            large.pop_back();
            small.push_back(l);
        }
    }
    // Leftovers are 1 up to rounding.
    for (uint32_t i : small) m_bins[i] = {1.0f, i, m_bins[i].pmf};
    for (uint32_t i : large) m_bins[i] = {1.0f, i, m_bins[i].pmf};
}

}  // namespace npt
