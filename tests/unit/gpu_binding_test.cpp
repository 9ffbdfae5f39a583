// One GPU per MPI rank (dist/gpu_binding.h) and how nerfpt tells it was started by an MPI launcher
// (dist/mpi_world.h): pure functions of the environment.
#include "dist/gpu_binding.h"

#include <gtest/gtest.h>

#include <map>
#include <string>

#include "dist/mpi_world.h"

namespace npt::dist {
namespace {

std::map<std::string, std::string>* g_binding_env = nullptr;
const char* fake_binding_getenv(const char* name) {
    const auto it = g_binding_env->find(name);
    return it == g_binding_env->end() ? nullptr : it->second.c_str();
}

TEST(GpuBinding, LocalRankTakesItsGpu) {
    EXPECT_EQ(cuda_devices_for_rank(0, nullptr, 4), "0");
    EXPECT_EQ(cuda_devices_for_rank(3, nullptr, 4), "3");
    EXPECT_EQ(cuda_devices_for_rank(5, nullptr, 4), "1");  // more ranks than GPUs: shared in turn
    EXPECT_EQ(cuda_devices_for_rank(1, "", 2), "1");       // empty: as if unset
    EXPECT_EQ(cuda_devices_for_rank(1, "4,6,7", 8), "6");  // a scheduler's list: its entries
    EXPECT_EQ(cuda_devices_for_rank(4, "4,6,7", 8), "6");
    EXPECT_FALSE(cuda_devices_for_rank(1, "5", 8));      // one GPU chosen already
    EXPECT_FALSE(cuda_devices_for_rank(1, nullptr, 1));  // nothing to choose
    EXPECT_FALSE(cuda_devices_for_rank(1, nullptr, 0));
    EXPECT_FALSE(cuda_devices_for_rank(-1, nullptr, 4));  // no local rank known
}

TEST(GpuBinding, LauncherEnvironment) {
    std::map<std::string, std::string> env;
    g_binding_env = &env;
    EXPECT_EQ(launcher_world_size(fake_binding_getenv), 0);
    EXPECT_EQ(launcher_local_rank(fake_binding_getenv), -1);
    env = {{"OMPI_COMM_WORLD_SIZE", "4"}, {"OMPI_COMM_WORLD_LOCAL_RANK", "2"}};
    EXPECT_EQ(launcher_world_size(fake_binding_getenv), 4);
    EXPECT_EQ(launcher_local_rank(fake_binding_getenv), 2);
    env = {{"PMI_SIZE", "8"}, {"MPI_LOCALRANKID", "1"}};
    EXPECT_EQ(launcher_world_size(fake_binding_getenv), 8);
    EXPECT_EQ(launcher_local_rank(fake_binding_getenv), 1);
    env = {{"PMIX_RANK", "0"}, {"SLURM_LOCALID", "3"}};
    EXPECT_EQ(launcher_world_size(fake_binding_getenv), 1);
    EXPECT_EQ(launcher_local_rank(fake_binding_getenv), 3);
    env = {{"OMPI_COMM_WORLD_SIZE", "x"}, {"OMPI_COMM_WORLD_LOCAL_RANK", "-1"}};
    EXPECT_EQ(launcher_world_size(fake_binding_getenv), 0);
    EXPECT_EQ(launcher_local_rank(fake_binding_getenv), -1);
    g_binding_env = nullptr;
}

TEST(GpuBinding, AWorldOfOneWithoutALauncher) {
    if (launcher_world_size([](const char* n) -> const char* { return std::getenv(n); }) != 0)
        GTEST_SKIP() << "the test itself runs under an MPI launcher";
    MpiWorld world;
    EXPECT_EQ(world.size(), 1);
    EXPECT_EQ(world.rank(), 0);
    EXPECT_FALSE(world.agree({}));
    EXPECT_EQ(*world.agree("boom"), "rank 0 of 1 on " + world.host() + ": boom");
}

}  // namespace
}  // namespace npt::dist
