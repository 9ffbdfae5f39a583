#include "nerf/relight/field_query.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <vector>

#include "nerf/field_batch.h"

namespace npt::nerf {

namespace {

constexpr size_t k_queries_per_task = 2048;

class CpuFieldQuery final : public FieldQuery {
  public:
    explicit CpuFieldQuery(const NerfModel& model) : m_layout(model.layout()), m_params(model.params.data()) {}
    void evaluate(const Vec3* positions, const Vec3* dirs, size_t n, float* sigma, Rgb* rgb) override {
        const size_t chunks = (n + k_queries_per_task - 1) / k_queries_per_task;
        tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
            thread_local FieldBatch batch;
            const size_t b = c * k_queries_per_task, m = std::min(k_queries_per_task, n - b);
            field_forward(m_layout, m_params, positions + b, dirs ? dirs + b : nullptr, m, dirs != nullptr, batch);
            std::copy(batch.sigma.begin(), batch.sigma.begin() + m, sigma + b);
            if (dirs) std::copy(batch.rgb.begin(), batch.rgb.begin() + m, rgb + b);
        });
    }

  private:
    NerfLayout m_layout;
    const float* m_params;
};

}  // namespace

std::unique_ptr<FieldQuery> make_cpu_field_query(const NerfModel& model) {
    return std::make_unique<CpuFieldQuery>(model);
}

}  // namespace npt::nerf
