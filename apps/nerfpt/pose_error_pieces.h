// `nerfpt pose-error --pieces`: a reference made of rigid pieces misplaced against each other (a COLMAP model
// that registered stretches of a video on the wrong side) fits no single similarity, so each continuous piece
// of its camera path (capture/path_continuity.h) is aligned and measured on its own.
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "capture/pose_alignment.h"

namespace npt::cli {

struct PieceComparison {
    std::string first, last;                            // reference names at the piece's ends, in name order
    size_t images = 0;                                  // reference poses in the piece
    size_t matched = 0;                                 // of them, paired with the estimate
    std::optional<capture::PoseComparison> comparison;  // empty when not aligned: why_not says why
    std::string why_not;
};

// Cuts the reference (any order) at its path jumps and compares the matched pairs of each piece alone.
std::vector<PieceComparison> compare_pieces(const std::vector<capture::CameraPose>& reference,
                                            const capture::MatchedPoses& matched);

void print_pieces(const std::vector<PieceComparison>& pieces);
nlohmann::json pieces_json(const std::vector<PieceComparison>& pieces);

}  // namespace npt::cli
