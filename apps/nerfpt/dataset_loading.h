// Loading a NeRF data set from the command line: the images load with a progress bar, then shrink by
// --downscale. Shared by train and eval.
#pragma once

#include <string>

#include "nerf/dataset.h"

namespace npt::cli {

nerf::Dataset load_dataset_with_progress(const std::string& data, const std::string& split, int downscale,
                                         bool quiet);

}  // namespace npt::cli
