#include "omma/dist/comm.h"

#include <cstdlib>

#include <gtest/gtest.h>

namespace omma::dist {
namespace {

TEST(Comm, LocalCommIsOneRank) {
  LocalComm c;
  EXPECT_EQ(c.rank(), 0);
  EXPECT_EQ(c.size(), 1);
  EXPECT_EQ(c.broadcast("x"), "x");
  EXPECT_EQ(c.gather("y"), std::vector<std::string>{"y"});
  EXPECT_FALSE(c.try_recv().has_value());
  EXPECT_THROW(c.send(1, 0, "z"), std::logic_error);
  EXPECT_FALSE(c.host().empty());
}

TEST(Comm, LauncherDetectionAndABuildWithoutMpiUnderMpirun) {
  unsetenv("OMPI_COMM_WORLD_SIZE");
  unsetenv("PMI_SIZE");
  unsetenv("PMIX_RANK");
  int n = -1;
  EXPECT_FALSE(launched_by_mpi(&n));
  EXPECT_EQ(n, 0);
  EXPECT_FALSE(make_comm()->is_mpi());  // not under mpirun: one process, with or without MPI
  setenv("OMPI_COMM_WORLD_SIZE", "3", 1);
  EXPECT_TRUE(launched_by_mpi(&n));
  EXPECT_EQ(n, 3);
  if (!built_with_mpi()) {
    // Each of the 3 processes would do the whole job on its own: refuse, and say why.
    try {
      make_comm();
      ADD_FAILURE() << "no error";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("built without MPI"), std::string::npos) << e.what();
    }
  }
  unsetenv("OMPI_COMM_WORLD_SIZE");
}

}  // namespace
}  // namespace omma::dist
