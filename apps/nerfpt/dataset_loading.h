// Loading a NeRF data set from the command line: the images load with a progress bar, then shrink by
// --downscale. Shared by train and eval.
#pragma once

#include <string>
#include <vector>

#include "input_checks.h"
#include "nerf/dataset.h"

namespace npt::cli {

nerf::Dataset load_dataset_with_progress(const std::string& data, const std::string& split, int downscale,
                                         bool quiet);

// The files a loaded data set was read from (its transforms.json and every image), plus `extra`, for
// refuse_overwriting_inputs.
std::vector<InputFile> dataset_inputs(const nerf::Dataset& data, std::vector<InputFile> extra = {});

}  // namespace npt::cli
