#include "dataset_loading.h"

#include <iostream>

#include "core/progress.h"

namespace npt::cli {

nerf::Dataset load_dataset_with_progress(const std::string& data, const std::string& split, int downscale,
                                         bool quiet) {
    ProgressSettings ps;
    ps.label = "load";
    ps.unit = "images";
    ps.style = progress_style(stream_is_tty(stderr), quiet);
    Progress progress(ps, std::cerr);
    nerf::Dataset ds =
        nerf::load_dataset(data, split, [&](size_t done, size_t total) { progress.update(done, total); });
    progress.finish();
    nerf::downscale_dataset(ds, downscale);
    return ds;
}

std::vector<InputFile> dataset_inputs(const nerf::Dataset& data, std::vector<InputFile> extra) {
    extra.push_back({"DATA", data.source});
    for (size_t i = 0; i < data.image_files.size(); ++i)
        extra.push_back({"DATA's image of frame " + std::to_string(i), data.image_files[i]});
    return extra;
}

}  // namespace npt::cli
