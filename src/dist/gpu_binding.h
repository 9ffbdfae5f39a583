// One GPU per MPI rank on a node with several: rank k of the node takes GPU k mod (GPUs). Done by setting
// CUDA_VISIBLE_DEVICES before anything starts CUDA, so that every CUDA and OptiX context of the process
// (which all take "device 0") lands on that GPU without the renderers knowing about ranks.
#pragma once

#include <optional>
#include <string>

namespace npt::dist {

// The value CUDA_VISIBLE_DEVICES should take for local rank `local_rank`: with `visible` set (a scheduler's
// or the user's list, e.g. "0,2,3") its (local_rank mod count)-th entry; else, with `gpus_on_node` > 1, that
// index. Nothing when there is nothing to choose (one GPU or none, or `visible` already one entry).
std::optional<std::string> cuda_devices_for_rank(int local_rank, const char* visible, int gpus_on_node);

// This node's NVIDIA GPUs as the driver lists them (/proc/driver/nvidia/gpus), without starting CUDA; 0 when
// there is no driver.
int nvidia_gpus_on_node();

// The local rank from the launcher's environment (OMPI_COMM_WORLD_LOCAL_RANK, MPI_LOCALRANKID, SLURM_LOCALID,
// PMIX... ), -1 when none says.
int launcher_local_rank(const char* (*getenv)(const char*));

}  // namespace npt::dist
