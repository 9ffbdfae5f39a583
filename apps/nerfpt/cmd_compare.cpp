#include "cmd_compare.h"

#include <fmt/format.h>

#include "core/error.h"
#include "core/image_io.h"
#include "core/image_stats.h"

namespace npt::cli {

CLI::App* add_compare_command(CLI::App& app, CompareArgs& args) {
    CLI::App* cmd = app.add_subcommand(
        "compare",
        "Compare an image with a reference: relative MSE mean((x-r)^2/(r^2+0.01)) over pixels and RGB, "
        "and the image mean per channel. Both images must have the same size (EXR, HDR or PNG).");
    cmd->add_option("IMAGE", args.image, "The image to judge")->required()->check(CLI::ExistingFile);
    cmd->add_option("REFERENCE", args.reference, "The reference image")->required()->check(CLI::ExistingFile);
    return cmd;
}

int run_compare(const CompareArgs& args, const GlobalSettings&) {
    Image image = read_image(args.image);
    Image ref = read_image(args.reference);
    const auto size = [](const Image& i) { return std::to_string(i.width) + "x" + std::to_string(i.height); };
    if (image.width != ref.width || image.height != ref.height)
        throw Error("IMAGE '" + args.image + "' is " + size(image) + " but REFERENCE '" + args.reference +
                    "' is " + size(ref) + ": compare needs images of the same size");
    ImageComparison c = compare_images(image, ref);
    fmt::print("relMSE     {:.4g}\n", c.rel_mse);
    const char* names[3] = {"R", "G", "B"};
    for (size_t k = 0; k < 3; ++k)
        fmt::print("mean {}     {:.5f} vs {:.5f} (relative {:+.2e})\n", names[k], c.mean_test[k],
                   c.mean_ref[k], c.mean_rel_err[k]);
    return 0;
}

}  // namespace npt::cli
