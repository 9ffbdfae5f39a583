#include "dist/frames.h"

#include <algorithm>
#include <cstdlib>

#include "core/error.h"

namespace npt::dist {

namespace {

constexpr int k_max_frame = 9999999;

// A whole number 0..k_max_frame, digits only.
std::optional<int> frame_number(const std::string& s) {
    if (s.empty() || s.size() > 7 || !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }))
        return std::nullopt;
    return std::stoi(s);
}

uint64_t mix64(uint64_t z) {  // SplitMix64's finaliser
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

}  // namespace

std::vector<int> FrameRange::frames() const {
    std::vector<int> out;
    for (long long f = first; f <= last; f += step) out.push_back(int(f));
    return out;
}

FrameRange parse_frame_range(const std::string& text, const std::string& option) {
    const auto bad = [&](const std::string& why) {
        return Error(option + ": '" + text + "' " + why + " (FIRST-LAST[:STEP] such as 1-240 or 1-240:2, or one frame)");
    };
    FrameRange r;
    std::string range = text;
    if (const size_t colon = text.find(':'); colon != std::string::npos) {
        range = text.substr(0, colon);
        const auto step = frame_number(text.substr(colon + 1));
        if (!step || *step < 1) throw bad("has a step that is not a whole number >= 1");
        r.step = *step;
    }
    const size_t dash = range.find('-');
    const auto first = frame_number(range.substr(0, dash));
    const auto last = dash == std::string::npos ? first : frame_number(range.substr(dash + 1));
    if (!first || !last) throw bad("is not a range of whole frame numbers 0.." + std::to_string(k_max_frame));
    if (*last < *first) throw bad("ends before it starts");
    r.first = *first;
    r.last = *last;
    return r;
}

std::vector<int> task_frames(const std::vector<int>& frames, int index, int count) {
    if (count < 1 || index < 0 || index >= count)
        throw Error("task " + std::to_string(index) + " of " + std::to_string(count) + ": the index must be in [0, count)");
    const size_t n = frames.size(), c = size_t(count), i = size_t(index);
    const size_t base = n / c, extra = n % c;
    const size_t begin = i * base + std::min(i, extra);
    const size_t size = base + (i < extra ? 1 : 0);
    return std::vector<int>(frames.begin() + std::ptrdiff_t(begin), frames.begin() + std::ptrdiff_t(begin + size));
}

TaskSlot resolve_task(std::optional<int> index, std::optional<int> count, const char* (*getenv)(const char*)) {
    const auto env_int = [&](const char* name) -> std::optional<int> {
        const char* v = getenv(name);
        if (!v || !*v) return std::nullopt;
        const std::string s(v);
        if (s.size() > 9 || !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }))
            throw Error(std::string(name) + "='" + s + "': expected a whole number >= 0");
        return std::stoi(s);
    };
    TaskSlot t;
    if (index || count) {
        if (!index || !count) throw Error("--task-index and --task-count go together");
        t = {*index, *count};
        if (t.count < 1) throw Error("--task-count: " + std::to_string(t.count) + " must be >= 1");
        if (t.index < 0 || t.index >= t.count)
            throw Error("--task-index: " + std::to_string(t.index) + " must be in 0.." + std::to_string(t.count - 1));
        return t;
    }
    const auto id = env_int("SLURM_ARRAY_TASK_ID");
    const auto n = env_int("SLURM_ARRAY_TASK_COUNT");
    if (!id && !n) return t;
    if (!id || !n) throw Error("SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT: one is set without the other");
    const int min = env_int("SLURM_ARRAY_TASK_MIN").value_or(0);
    t = {*id - min, *n};
    if (t.count < 1) throw Error("SLURM_ARRAY_TASK_COUNT=" + std::to_string(t.count) + ": must be >= 1");
    if (t.index < 0 || t.index >= t.count)
        throw Error("SLURM_ARRAY_TASK_ID=" + std::to_string(*id) + " (minus SLURM_ARRAY_TASK_MIN=" + std::to_string(min) +
                    "): not in 0.." + std::to_string(t.count - 1) +
                    " (number the array 0..N-1 or 1..N, with a step of 1)");
    return t;
}

bool has_frame_pattern(const std::filesystem::path& pattern) {
    return pattern.filename().string().find('#') != std::string::npos;
}

std::filesystem::path frame_path(const std::filesystem::path& pattern, int frame) {
    std::string name = pattern.filename().string();
    const size_t end = name.rfind('#');
    if (end == std::string::npos)
        throw Error("--output '" + pattern.string() + "': a sequence needs #### in the file name (shot.####.exr)");
    size_t begin = end;
    while (begin > 0 && name[begin - 1] == '#') --begin;
    std::string number = std::to_string(frame);
    const size_t width = end - begin + 1;
    if (number.size() < width) number.insert(0, width - number.size(), '0');
    name.replace(begin, width, number);
    return pattern.parent_path() / name;
}

uint64_t frame_seed(uint64_t seed, int frame) {
    return mix64(mix64(seed + 0x9E3779B97F4A7C15ull) ^ (uint64_t(uint32_t(frame)) * 0xD1B54A32D192ED03ull));
}

}  // namespace npt::dist
