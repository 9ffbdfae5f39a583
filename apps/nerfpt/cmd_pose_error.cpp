#include "cmd_pose_error.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>

#include "capture/colmap_model.h"
#include "capture/pose_alignment.h"
#include "core/error.h"
#include "core/temp_file.h"
#include "input_checks.h"
#include "pose_error_pieces.h"

namespace npt::cli {
namespace fs = std::filesystem;
using capture::CameraPose;

CLI::App* add_pose_error_command(CLI::App& app, PoseErrorArgs& args) {
    CLI::App* cmd = app.add_subcommand("pose-error",
                                       "Compare camera poses with a reference after a similarity alignment");
    cmd->footer(
        "ESTIMATE and REFERENCE are each a transforms.json (or a folder holding one) or a COLMAP sparse "
        "model\n"
        "folder (cameras.bin, images.bin, points3D.bin). The estimate's camera centres are aligned to the\n"
        "reference's by the least-squares similarity (Umeyama: scale, rotation, translation); then per "
        "camera\n"
        "the centre error (reference units, and % of the reference trajectory's RMS radius) and the "
        "rotation\n"
        "error (degrees) are reported as mean, median and max.\n"
        "--match name: cameras with the same image file name. --match rate: the reference's frames, in name\n"
        "order, were extracted from the same video at a constant rate (reference frame i = video frame a i + "
        "b,\n"
        "a and b unknown) and the estimate's names carry their video frame number (frame_00012.png, as\n"
        "'nerfpt curate' writes them); a and b are searched (a in 0.5..30) for the smallest median centre "
        "error\n"
        "and the estimate is interpolated at each reference frame (docs/formats.md, 'Comparing poses'); "
        "give\n"
        "them with --known-rate when the extraction is known (ffmpeg -vf fps=3 on a 30 fps video: 10 0).\n"
        "--pieces: the reference, in name order, is cut into continuous pieces where its camera path\n"
        "leaps between neighbouring images (a step over 8 times the median step), and each piece with 3\n"
        "or more matched cameras is aligned by its own similarity: after the global table, one row per\n"
        "piece (rotation median and max in degrees, centre median and max in % of that piece's\n"
        "trajectory scale, the piece's alignment scale).\n"
        "Example: nerfpt pose-error out/beer/transforms.json ../shared/data/captures/beer/sparse/0 --match "
        "rate");
    cmd->add_option("ESTIMATE", args.estimate, "Poses to judge: transforms.json or COLMAP model folder")
        ->required();
    cmd->add_option("REFERENCE", args.reference, "Reference poses: transforms.json or COLMAP model folder")
        ->required();
    cmd->add_option("--match", args.match, "How cameras are paired: name or rate (default: name)")
        ->check(CLI::IsMember({"name", "rate"}));
    cmd->add_option(
           "--known-rate", args.known_rate,
           "With --match rate: reference frame i is video frame A i + B; use these instead of searching")
        ->expected(2)
        ->type_name("A B");
    cmd->add_flag("--pieces", args.pieces,
                  "Also align and compare each continuous piece of the reference's camera path alone");
    cmd->add_option("--json", args.json, "Also write the numbers and per-camera errors to this JSON file");
    return cmd;
}

namespace {

std::vector<CameraPose> load_poses(const fs::path& path, const std::string& what) {
    require_path(path, what);
    std::error_code ec;
    if (!fs::is_directory(path, ec)) return capture::read_transforms_poses(path);
    if (fs::exists(path / "images.bin", ec)) return capture::colmap_poses(capture::read_colmap_model(path));
    if (fs::exists(path / "transforms.json", ec))
        return capture::read_transforms_poses(path / "transforms.json");
    throw Error(what + " '" + path.string() + "': folder holds neither a COLMAP model (images.bin) nor a " +
                "transforms.json");
}

// The last run of digits in the file name's stem: "frame_00012.png" -> 12.
std::optional<double> frame_number(const std::string& name) {
    const std::string stem = fs::path(name).stem().string();
    const size_t end = stem.find_last_of("0123456789");
    if (end == std::string::npos) return std::nullopt;
    const size_t before = stem.find_last_not_of("0123456789", end);
    const size_t begin = before == std::string::npos ? 0 : before + 1;
    return std::stod(stem.substr(begin, end - begin + 1));
}

nlohmann::json stats_json(const capture::ErrorStats& s, double factor = 1) {
    return {{"mean", s.mean * factor}, {"median", s.median * factor}, {"max", s.max * factor}};
}

}  // namespace

int run_pose_error(const PoseErrorArgs& args, const GlobalSettings& global) {
    if (!args.json.empty()) require_writable_parent(args.json, "--json");
    if (!args.known_rate.empty() && args.match != "rate") throw Error("--known-rate needs --match rate");
    if (!args.known_rate.empty() && !(args.known_rate[0] > 0))
        throw Error("--known-rate: A must be a positive number of video frames per reference frame");
    std::vector<CameraPose> estimate = load_poses(args.estimate, "ESTIMATE");
    std::vector<CameraPose> reference = load_poses(args.reference, "REFERENCE");

    capture::MatchedPoses matched;
    capture::PoseComparison c;
    std::optional<capture::TimeMapping> mapping;
    if (args.match == "name") {
        matched = capture::match_by_name(estimate, reference);
        if (matched.estimate.size() < 3)
            throw Error(
                fmt::format("only {} cameras share a file name between ESTIMATE and REFERENCE (need 3); "
                            "for frames of one video extracted differently try --match rate",
                            matched.estimate.size()));
        c = capture::compare_poses(matched.estimate, matched.reference);
    } else {
        std::vector<double> frames;
        for (const CameraPose& p : estimate) {
            const auto f = frame_number(p.name);
            if (!f)
                throw Error("ESTIMATE: '" + p.name +
                            "' has no frame number in its name (--match rate needs " +
                            "names like frame_00012.png)");
            frames.push_back(*f);
        }
        std::sort(reference.begin(), reference.end(),
                  [](const CameraPose& a, const CameraPose& b) { return a.name < b.name; });
        if (args.known_rate.empty()) {
            mapping = capture::fit_time_mapping(estimate, frames, reference);
        } else {
            mapping.emplace();
            mapping->a = args.known_rate[0];
            mapping->b = args.known_rate[1];
            std::vector<double> times;
            for (size_t i = 0; i < reference.size(); ++i)
                times.push_back(mapping->a * double(i) + mapping->b);
            mapping->matched = capture::match_by_time(estimate, frames, reference, times);
            mapping->comparison =
                capture::compare_poses(mapping->matched.estimate, mapping->matched.reference);
        }
        matched = mapping->matched;
        c = mapping->comparison;
    }

    const double rel = c.trajectory_scale > 0 ? 100 / c.trajectory_scale : 0;
    fmt::print("matched cameras       {} (unmatched: {} estimate, {} reference)\n", c.count,
               matched.unmatched_estimate, matched.unmatched_reference);
    if (mapping)
        fmt::print("frame rate mapping    reference frame i = video frame {:.4f} i + {:.2f}\n", mapping->a,
                   mapping->b);
    fmt::print("                      {:>10} {:>10} {:>10}\n", "mean", "median", "max");
    fmt::print("rotation error (deg)  {:>10.3f} {:>10.3f} {:>10.3f}\n", c.rotation_deg.mean,
               c.rotation_deg.median, c.rotation_deg.max);
    fmt::print("centre error          {:>10.4g} {:>10.4g} {:>10.4g}  reference units\n", c.centre.mean,
               c.centre.median, c.centre.max);
    fmt::print("centre error (%)      {:>10.3f} {:>10.3f} {:>10.3f}  of the trajectory scale {:.4g}\n",
               c.centre.mean * rel, c.centre.median * rel, c.centre.max * rel, c.trajectory_scale);
    fmt::print("alignment scale       {:.6g} (estimate units to reference units)\n", c.similarity.scale);
    std::vector<PieceComparison> pieces;
    if (args.pieces) {
        pieces = compare_pieces(reference, matched);
        print_pieces(pieces);
    }

    if (!args.json.empty()) {
        nlohmann::json cameras = nlohmann::json::array();
        for (size_t i = 0; i < c.count; ++i)
            cameras.push_back({{"estimate", matched.estimate[i].name},
                               {"reference", matched.reference[i].name},
                               {"rotation_deg", c.rotation_errors_deg[i]},
                               {"centre", c.centre_errors[i]}});
        nlohmann::json rotation = nlohmann::json::array();
        for (int r = 0; r < 3; ++r)
            rotation.push_back(
                {c.similarity.rotation(r, 0), c.similarity.rotation(r, 1), c.similarity.rotation(r, 2)});
        const auto& t = c.similarity.translation;
        nlohmann::json j = {
            {"estimate", args.estimate},
            {"reference", args.reference},
            {"match", args.match},
            {"matched", c.count},
            {"unmatched_estimate", matched.unmatched_estimate},
            {"unmatched_reference", matched.unmatched_reference},
            {"trajectory_scale", c.trajectory_scale},
            {"rotation_deg", stats_json(c.rotation_deg)},
            {"centre", stats_json(c.centre)},
            {"centre_percent", stats_json(c.centre, rel)},
            {"similarity",
             {{"scale", c.similarity.scale}, {"rotation", rotation}, {"translation", {t[0], t[1], t[2]}}}},
            {"cameras", cameras}};
        if (mapping) j["rate"] = {{"a", mapping->a}, {"b", mapping->b}};
        if (args.pieces) j["pieces"] = pieces_json(pieces);
        write_text_atomic(args.json, j.dump(2) + "\n");
        if (!global.quiet) fmt::print("wrote {}\n", args.json);
    }
    return 0;
}

}  // namespace npt::cli
