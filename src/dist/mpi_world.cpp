#include "dist/mpi_world.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <cstdlib>

#include "core/error.h"
#include "dist/gpu_binding.h"

#if NERFPT_HAVE_MPI
#include <mpi.h>
#endif

namespace npt::dist {

namespace {

std::optional<int> whole_number(const char* v) {
    if (!v || !*v) return std::nullopt;
    const std::string s(v);
    if (s.size() > 7 || !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }))
        return std::nullopt;
    return std::stoi(s);
}

std::string host_name() {
    char name[256] = {};
    if (gethostname(name, sizeof name - 1) != 0) return "?";
    return name;
}

const char* env(const char* name) { return std::getenv(name); }

}  // namespace

bool mpi_built() { return NERFPT_HAVE_MPI != 0; }

int launcher_world_size(const char* (*getenv)(const char*)) {
    for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "MV2_COMM_WORLD_SIZE"})
        if (const auto v = whole_number(getenv(name)); v && *v > 0) return *v;
    if (getenv("PMIX_RANK")) return 1;  // PMIx says it started us, not how many: MPI_Init will
    return 0;
}

std::string MpiWorld::name() const { return fmt::format("rank {} of {} on {}", m_rank, m_size, m_host); }

MpiWorld::MpiWorld() : m_host(host_name()) {
    const int launched = launcher_world_size(env);
    if (launched == 0) return;
    // Before MPI or anything else can start CUDA.
    if (const auto devices = cuda_devices_for_rank(launcher_local_rank(env), env("CUDA_VISIBLE_DEVICES"),
                                                   nvidia_gpus_on_node())) {
        setenv("CUDA_VISIBLE_DEVICES", devices->c_str(), 1);
        m_gpu_note = "CUDA_VISIBLE_DEVICES=" + *devices;
    }
#if NERFPT_HAVE_MPI
    int provided = 0;
    if (MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
        throw Error("MPI_Init failed (started by an MPI launcher as one of " + std::to_string(launched) +
                    " processes)");
    m_started = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &m_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &m_size);
    MPI_Comm node;
    MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, m_rank, MPI_INFO_NULL, &node);
    MPI_Comm_rank(node, &m_local_rank);
    MPI_Comm_free(&node);
#else
    if (launched > 1)
        throw Error(
            "started by an MPI launcher as one of " + std::to_string(launched) +
            " processes, but this nerfpt was built without MPI (each process would render the whole job); "
            "build it with Open MPI (libopenmpi-dev, cmake -DNERFPT_MPI=ON) or run one process");
#endif
}

MpiWorld::~MpiWorld() {
#if NERFPT_HAVE_MPI
    if (m_started) MPI_Finalize();
#endif
}

#if NERFPT_HAVE_MPI

namespace {

constexpr int k_tag_size = 1, k_tag_bytes = 2;
constexpr size_t k_chunk = size_t(1) << 30;  // MPI counts are ints: large messages go in 1 GiB pieces

void send_bytes(const std::vector<char>& bytes, int dest) {
    const uint64_t n = bytes.size();
    MPI_Send(&n, 1, MPI_UINT64_T, dest, k_tag_size, MPI_COMM_WORLD);
    for (size_t off = 0; off < n; off += k_chunk)
        MPI_Send(bytes.data() + off, int(std::min(k_chunk, n - off)), MPI_BYTE, dest, k_tag_bytes,
                 MPI_COMM_WORLD);
}

std::vector<char> recv_bytes(int source) {
    uint64_t n = 0;
    MPI_Recv(&n, 1, MPI_UINT64_T, source, k_tag_size, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    std::vector<char> bytes(n);
    for (size_t off = 0; off < n; off += k_chunk)
        MPI_Recv(bytes.data() + off, int(std::min(k_chunk, size_t(n) - off)), MPI_BYTE, source, k_tag_bytes,
                 MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    return bytes;
}

}  // namespace

std::optional<std::string> MpiWorld::agree(const std::string& error) {
    if (!m_started) return error.empty() ? std::nullopt : std::optional<std::string>(name() + ": " + error);
    // Every rank's message (most are empty) to every rank.
    const std::string mine = error.substr(0, 4000);
    int length = int(mine.size());
    std::vector<int> lengths(static_cast<size_t>(m_size));
    MPI_Allgather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, MPI_COMM_WORLD);
    std::vector<int> offsets(static_cast<size_t>(m_size), 0);
    for (int r = 1; r < m_size; ++r) offsets[size_t(r)] = offsets[size_t(r - 1)] + lengths[size_t(r - 1)];
    std::string all(size_t(offsets.back() + lengths.back()), '\0');
    MPI_Allgatherv(mine.data(), length, MPI_CHAR, all.data(), lengths.data(), offsets.data(), MPI_CHAR,
                   MPI_COMM_WORLD);
    int first = -1, failed = 0;
    for (int r = 0; r < m_size; ++r)
        if (lengths[size_t(r)] > 0) {
            if (first < 0) first = r;
            ++failed;
        }
    if (first < 0) return std::nullopt;
    // The failed rank's host: every rank's, gathered only now that it is needed.
    char host[64] = {};
    m_host.copy(host, sizeof host - 1);
    std::vector<char> hosts(size_t(m_size) * sizeof host);
    MPI_Allgather(host, sizeof host, MPI_CHAR, hosts.data(), sizeof host, MPI_CHAR, MPI_COMM_WORLD);
    std::string line = fmt::format(
        "rank {} of {} on {}: {}", first, m_size, std::string(&hosts[size_t(first) * sizeof host]),
        all.substr(size_t(offsets[size_t(first)]), size_t(lengths[size_t(first)])));
    if (failed > 1) line += fmt::format(" ({} other rank{} failed too)", failed - 1, failed > 2 ? "s" : "");
    return line;
}

void MpiWorld::broadcast(std::vector<int>& values) {
    if (!m_started) return;
    uint64_t n = values.size();
    MPI_Bcast(&n, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
    values.resize(n);
    if (n > 0) MPI_Bcast(values.data(), int(n), MPI_INT, 0, MPI_COMM_WORLD);
}

void MpiWorld::reduce_in_rank_order(
    std::vector<char>& bytes,
    const std::function<void(std::vector<char>& left, std::vector<char>&& right)>& merge) {
    if (!m_started) return;
    for (int step = 1; step < m_size; step *= 2) {
        if (m_rank % (2 * step) == step) {  // this rank's part is complete: to the rank on its left, and done
            send_bytes(bytes, m_rank - step);
            bytes.clear();
            return;
        }
        if (m_rank % (2 * step) == 0 && m_rank + step < m_size) {
            try {
                merge(bytes, recv_bytes(m_rank + step));
            } catch (const std::exception& e) {
                // The ranks on the right wait in sends: end the whole job rather than hang it.
                fmt::print(stderr, "nerfpt: error: {}: merging rank {}'s result: {}\n", name(), m_rank + step,
                           e.what());
                MPI_Abort(MPI_COMM_WORLD, 1);
            }
        }
    }
}

#else

std::optional<std::string> MpiWorld::agree(const std::string& error) {
    return error.empty() ? std::nullopt : std::optional<std::string>(name() + ": " + error);
}
void MpiWorld::broadcast(std::vector<int>&) {}
void MpiWorld::reduce_in_rank_order(std::vector<char>&,
                                    const std::function<void(std::vector<char>&, std::vector<char>&&)>&) {}

#endif

}  // namespace npt::dist
