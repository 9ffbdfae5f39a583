// One training step at a time of a NerfModel on a Dataset (CPU, TBB): sample rays from random pixels of
// random views, march them through the occupancy grid, evaluate the field in fixed-size chunks, composite
// against a random background, Huber loss, backpropagate, Adam; refresh the occupancy grid every few steps.
// Every random number is a function of (seed, step, ray), and every sum runs in a fixed order, so a run is
// reproducible for a seed whatever the thread count, and continues exactly from a saved TrainingState.
#pragma once

#include <cstdint>
#include <memory>

#include "nerf/adam.h"
#include "nerf/dataset.h"
#include "nerf/nerf_model.h"

namespace npt::nerf {

struct StepStats {
    uint64_t step = 0;        // steps completed after this one
    double loss = 0;          // mean Huber loss per ray (summed over channels)
    double mse = 0;           // mean squared error per channel, for a training PSNR
    double smoothness = 0;    // mean surface-smoothness loss per group of rays (0 when it is off)
    uint32_t rays = 0;        // rays in the batch
    uint32_t samples = 0;     // samples trained on: those before each ray's early stop
    uint32_t marched = 0;     // samples marched and evaluated (the CPU trainer evaluates them all)
    double seconds = 0;       // wall time of the step
    bool occupancy_updated = false;
    // Where the step's time went, for profiles and benchmarks.
    struct Phases {
        double march = 0, forward = 0, loss = 0, backward = 0, grid_backward = 0, adam = 0, occupancy = 0;
    } phases;
};

class Trainer {
public:
    // The model must have been made for this data set (create_model) or loaded with its training state.
    // A model without a training state (e.g. loaded from a file saved without it) starts one from its
    // parameters. Throws npt::Error when the data set is empty.
    Trainer(NerfModel& model, const Dataset& data);

    StepStats step();
    uint64_t steps_done() const { return m_adam.steps(); }
    // The gradient step() would apply next (mean loss over the batch's rays, before L2), into grads (the
    // model's layout); the model and the optimizer do not change. For tests against the GPU trainer.
    StepStats gradient(std::vector<float>& grads);

    // Copies the optimizer state and the averaged parameters into the model, ready to save.
    void sync_model();

private:
    StepStats compute_gradient();  // marching to the hash-grid backward: fills m_grads
    void update_occupancy(uint64_t step);
    void clear_grid_gradient();  // the reached entries' gradients and flags back to zero (sparse_grid)

    NerfModel& m_model;
    const Dataset& m_data;
    NerfLayout m_layout;
    MarchParams m_march;
    Adam m_adam;
    std::vector<float> m_grads;  // with optimizer.sparse_grid, its grid range is zero between steps
    std::vector<uint8_t> m_reached;  // per hash-grid entry: reached by this step's samples (sparse_grid)
    std::vector<Rgb> m_exposure_grad;  // per training image: d loss / d log gain (training.exposure_per_image)
    uint64_t m_occupancy_interval = 16;  // steps between occupancy updates
};

// Training PSNR from a mean squared error over [0,1] values.
inline double psnr_from_mse(double mse) { return mse > 0 ? -10.0 * std::log10(mse) : 99.0; }

}  // namespace npt::nerf
