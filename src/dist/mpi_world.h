// nerfpt under mpirun: the ranks of the job and the few collective steps a render needs (agreeing that every
// rank's part went well, rank 0's list to all, a reduction in rank order). The only code that includes mpi.h
// is mpi_world.cpp; built without MPI (NERFPT_MPI off or Open MPI not found), a world is one process, and a
// start by mpirun with several processes is refused (each would render the whole job).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace npt::dist {

// True when this binary was built with MPI.
bool mpi_built();

// The number of processes an MPI launcher started this one among (OMPI_COMM_WORLD_SIZE of Open MPI's mpirun,
// PMI_SIZE of MPICH's and srun's PMI, PMIX_SIZE... ), or 0 when no launcher did. `getenv` as in frames.h.
int launcher_world_size(const char* (*getenv)(const char*));

// Another rank failed and rank 0 has said so: this rank stops without printing anything more.
struct PeerFailed : std::runtime_error {
    PeerFailed() : std::runtime_error("another MPI rank failed") {}
};

class MpiWorld {
  public:
    // Starts MPI when an MPI launcher started this process (launcher_world_size() > 0); before that, binds
    // this rank to one GPU of its node (gpu_binding.h), so that every CUDA context the process makes is
    // there. Throws npt::Error when launched with several processes by a nerfpt built without MPI.
    MpiWorld();
    ~MpiWorld();  // MPI_Finalize
    MpiWorld(const MpiWorld&) = delete;
    MpiWorld& operator=(const MpiWorld&) = delete;

    int rank() const { return m_rank; }
    int size() const { return m_size; }
    int local_rank() const { return m_local_rank; }  // among the ranks of this node
    const std::string& host() const { return m_host; }
    // "rank 1 of 4 on node7"
    std::string name() const;
    // The GPU binding made before MPI started, for the log ("" when none was made).
    const std::string& gpu_note() const { return m_gpu_note; }

    // Collective, every rank: `error` is empty when this rank's part went well. Returns nothing when every
    // rank's did; otherwise, on every rank, one line naming the first rank that failed, its message and how
    // many others failed ("rank 1 of 4 on node7: ... (2 other ranks failed too)").
    std::optional<std::string> agree(const std::string& error);

    // Collective: rank 0's values to every rank.
    void broadcast(std::vector<int>& values);

    // Collective: each rank's `bytes`, combined in rank order along a binomial tree (rank r + 2^k's result
    // merged into rank r's as merge(left = r's, right = r+2^k's)); rank 0 ends with the whole, others with
    // nothing useful. O(log size) steps, each moving one rank's partial result.
    void reduce_in_rank_order(
        std::vector<char>& bytes,
        const std::function<void(std::vector<char>& left, std::vector<char>&& right)>& merge);

  private:
    int m_rank = 0, m_size = 1, m_local_rank = 0;
    bool m_started = false;
    std::string m_host, m_gpu_note;
};

}  // namespace npt::dist
