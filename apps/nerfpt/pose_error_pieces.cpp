#include "pose_error_pieces.h"

#include <fmt/format.h>

#include <algorithm>
#include <unordered_map>

#include "capture/path_continuity.h"
#include "core/error.h"

namespace npt::cli {
using capture::CameraPose;

std::vector<PieceComparison> compare_pieces(const std::vector<CameraPose>& reference,
                                            const capture::MatchedPoses& matched) {
    std::vector<CameraPose> sorted = reference;
    std::sort(sorted.begin(), sorted.end(),
              [](const CameraPose& a, const CameraPose& b) { return a.name < b.name; });
    std::unordered_map<std::string, size_t> piece_of;
    std::vector<PieceComparison> pieces;
    for (const auto& [begin, end] : capture::continuous_pieces(sorted)) {
        for (size_t i = begin; i < end; ++i) piece_of[sorted[i].name] = pieces.size();
        pieces.push_back({sorted[begin].name, sorted[end - 1].name, end - begin});
    }
    std::vector<capture::MatchedPoses> pairs(pieces.size());
    for (size_t i = 0; i < matched.reference.size(); ++i) {
        capture::MatchedPoses& p = pairs[piece_of.at(matched.reference[i].name)];
        p.estimate.push_back(matched.estimate[i]);
        p.reference.push_back(matched.reference[i]);
    }
    for (size_t k = 0; k < pieces.size(); ++k) {
        pieces[k].matched = pairs[k].reference.size();
        if (pieces[k].matched < 3) {
            pieces[k].why_not = "fewer than 3 matched cameras";
            continue;
        }
        // A short piece can lie on one line; say so in its row instead of failing the whole report.
        try {
            pieces[k].comparison = capture::compare_poses(pairs[k].estimate, pairs[k].reference);
        } catch (const Error& e) {
            pieces[k].why_not = e.what();
        }
    }
    return pieces;
}

void print_pieces(const std::vector<PieceComparison>& pieces) {
    fmt::print("\npieces of the reference (cut where its camera path leaps), each aligned alone:\n");
    fmt::print("{:<32} {:>7} {:>8} {:>8} {:>10} {:>10} {:>10}\n", "reference images", "cameras", "rot med",
               "rot max", "centre med", "centre max", "scale");
    fmt::print("{:<32} {:>7} {:>8} {:>8} {:>10} {:>10}\n", "", "", "(deg)", "(deg)", "(%)", "(%)");
    for (const PieceComparison& p : pieces) {
        const std::string range = p.first + ".." + p.last;
        if (!p.comparison) {
            fmt::print("{:<32} {:>7}  not aligned: {}\n", range, p.matched, p.why_not);
            continue;
        }
        const capture::PoseComparison& c = *p.comparison;
        const double rel = c.trajectory_scale > 0 ? 100 / c.trajectory_scale : 0;
        fmt::print("{:<32} {:>7} {:>8.3f} {:>8.3f} {:>10.3f} {:>10.3f} {:>10.4g}\n", range, p.matched,
                   c.rotation_deg.median, c.rotation_deg.max, c.centre.median * rel, c.centre.max * rel,
                   c.similarity.scale);
    }
}

nlohmann::json pieces_json(const std::vector<PieceComparison>& pieces) {
    nlohmann::json out = nlohmann::json::array();
    for (const PieceComparison& p : pieces) {
        nlohmann::json j = {
            {"first", p.first}, {"last", p.last}, {"images", p.images}, {"matched", p.matched}};
        if (!p.comparison) {
            j["not_aligned"] = p.why_not;
        } else {
            const capture::PoseComparison& c = *p.comparison;
            const double rel = c.trajectory_scale > 0 ? 100 / c.trajectory_scale : 0;
            auto stats = [](const capture::ErrorStats& s, double f) {
                return nlohmann::json{{"mean", s.mean * f}, {"median", s.median * f}, {"max", s.max * f}};
            };
            j["trajectory_scale"] = c.trajectory_scale;
            j["rotation_deg"] = stats(c.rotation_deg, 1);
            j["centre"] = stats(c.centre, 1);
            j["centre_percent"] = stats(c.centre, rel);
            j["scale"] = c.similarity.scale;
        }
        out.push_back(j);
    }
    return out;
}

}  // namespace npt::cli
