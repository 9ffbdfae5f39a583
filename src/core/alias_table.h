// Walker/Vose alias table: O(1) sampling of a discrete distribution (lights by power).
// The table is built on the host into owned storage; AliasTableView is the POD that shared code samples.
#pragma once

#include <vector>

#include "core/platform.h"

namespace npt {

struct AliasBin {
    float q;      // probability of keeping this bin
    uint32_t alias;
    float pmf;    // the normalised probability of this bin, for MIS
};

struct AliasTableView {
    Span<const AliasBin> bins;

    // Returns the chosen index and its probability; `u` in [0,1) is consumed fully (the remainder is rescaled).
    NPT_HD uint32_t sample(float u, float* pmf) const {
        float scaled = u * float(bins.size);
        uint32_t i = uint32_t(scaled);
        if (i >= bins.size) i = uint32_t(bins.size - 1);
        float up = scaled - float(i);
        uint32_t chosen = up < bins[i].q ? i : bins[i].alias;
        *pmf = bins[chosen].pmf;
        return chosen;
    }
    NPT_HD float pmf(uint32_t i) const { return bins[i].pmf; }
};

class AliasTable {
public:
    AliasTable() = default;
    // Weights must be finite and non-negative; all-zero weights give an empty table.
    explicit AliasTable(const std::vector<double>& weights);
    AliasTableView view() const { return {{m_bins.data(), m_bins.size()}}; }
    size_t size() const { return m_bins.size(); }
    const std::vector<AliasBin>& bins() const { return m_bins; }

private:
    std::vector<AliasBin> m_bins;
};

}  // namespace npt
