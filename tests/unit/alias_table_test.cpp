#include "core/alias_table.h"

#include <gtest/gtest.h>

#include <vector>

#include "core/error.h"
#include "core/rng.h"

namespace npt {
namespace {

TEST(AliasTable, SampledFrequenciesMatchWeights) {
    std::vector<double> w = {1.0, 0.0, 3.0, 0.5, 5.5};
    AliasTable table(w);
    auto view = table.view();
    Pcg32 rng(7, 3);
    const int n = 200000;
    std::vector<int> count(w.size(), 0);
    for (int i = 0; i < n; ++i) {
        float pmf;
        uint32_t k = view.sample(rng.next_float(), &pmf);
        ASSERT_LT(k, w.size());
        EXPECT_FLOAT_EQ(pmf, float(w[k] / 10.0));
        ++count[k];
    }
    for (size_t k = 0; k < w.size(); ++k) {
        double p = w[k] / 10.0;
        double sigma = std::sqrt(n * p * (1 - p));
        // 5 standard deviations of a binomial count: fails for a wrong table, essentially never by chance.
        EXPECT_NEAR(count[k], n * p, 5 * sigma + 1) << "bin " << k;
    }
}

TEST(AliasTable, RejectsNegativeAndNaN) {
    EXPECT_THROW(AliasTable({1.0, -1.0}), Error);
    EXPECT_THROW(AliasTable({1.0, std::nan("")}), Error);
    EXPECT_EQ(AliasTable({0.0, 0.0}).size(), 0u);
}

}  // namespace
}  // namespace npt
