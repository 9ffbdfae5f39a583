#include "dist/gpu_binding.h"

#include <algorithm>
#include <filesystem>
#include <system_error>
#include <vector>

namespace npt::dist {

namespace {

std::optional<int> whole_number(const char* v) {
    if (!v || !*v) return std::nullopt;
    const std::string s(v);
    if (s.size() > 6 || !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }))
        return std::nullopt;
    return std::stoi(s);
}

}  // namespace

std::optional<std::string> cuda_devices_for_rank(int local_rank, const char* visible, int gpus_on_node) {
    if (local_rank < 0) return std::nullopt;
    if (visible && *visible) {
        std::vector<std::string> ids;
        std::string s(visible);
        size_t begin = 0;
        for (;;) {
            const size_t comma = s.find(',', begin);
            const std::string id =
                s.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin);
            if (!id.empty()) ids.push_back(id);
            if (comma == std::string::npos) break;
            begin = comma + 1;
        }
        if (ids.size() < 2) return std::nullopt;  // one GPU (or none: "" or "-1") chosen already
        return ids[size_t(local_rank) % ids.size()];
    }
    if (gpus_on_node < 2) return std::nullopt;
    return std::to_string(local_rank % gpus_on_node);
}

int nvidia_gpus_on_node() {
    std::error_code ec;
    std::filesystem::directory_iterator it("/proc/driver/nvidia/gpus", ec);
    if (ec) return 0;
    int n = 0;
    for (; it != std::filesystem::directory_iterator(); it.increment(ec)) {
        if (ec) break;
        ++n;
    }
    return n;
}

int launcher_local_rank(const char* (*getenv)(const char*)) {
    for (const char* name :
         {"OMPI_COMM_WORLD_LOCAL_RANK", "MPI_LOCALRANKID", "MV2_COMM_WORLD_LOCAL_RANK", "SLURM_LOCALID"})
        if (const auto v = whole_number(getenv(name))) return *v;
    return -1;
}

}  // namespace npt::dist
