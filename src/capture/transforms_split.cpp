#include "capture/transforms_split.h"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <string>

#include "core/error.h"
#include "core/json_file.h"
#include "core/temp_file.h"

namespace npt::capture {
namespace fs = std::filesystem;

namespace {

std::string file_path_of(const nlohmann::json& frame) {
    const auto it = frame.find("file_path");
    return it != frame.end() && it->is_string() ? it->get<std::string>() : std::string();
}

}  // namespace

SplitCounts split_transforms(const fs::path& json, int every) {
    const std::string where = json.string();
    if (every < 2)
        throw Error(where + ": a held-out split needs every >= 2 (got " + std::to_string(every) + ")");
    const nlohmann::json root = read_json_file(json);
    if (!root.is_object() || !root.contains("frames") || !root["frames"].is_array())
        throw Error(where + ": 'frames': expected an array");
    nlohmann::json frames = root["frames"];
    if (frames.size() < 2) throw Error(where + ": 'frames': a held-out split needs at least 2 frames");
    std::stable_sort(frames.begin(), frames.end(), [](const nlohmann::json& a, const nlohmann::json& b) {
        return file_path_of(a) < file_path_of(b);
    });
    nlohmann::json train = root, test = root;
    train["frames"] = nlohmann::json::array();
    test["frames"] = nlohmann::json::array();
    const size_t first = size_t(every / 2);
    for (size_t i = 0; i < frames.size(); ++i) {
        const bool held_out = i >= first && (i - first) % size_t(every) == 0;
        (held_out ? test : train)["frames"].push_back(frames[i]);
    }
    if (test["frames"].empty()) {  // fewer frames than every/2: hold out the last one
        test["frames"].push_back(frames.back());
        train["frames"].erase(train["frames"].size() - 1);
    }
    const fs::path dir = json.parent_path();
    write_text_atomic(dir / "transforms_train.json", train.dump(2) + "\n");
    write_text_atomic(dir / "transforms_test.json", test.dump(2) + "\n");
    return {train["frames"].size(), test["frames"].size()};
}

}  // namespace npt::capture
