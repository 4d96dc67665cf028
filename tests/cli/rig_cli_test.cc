// CLI tests for the generic behaviour of the command and `omma rig check`.
#include <fstream>

#include <gtest/gtest.h>

#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {

TEST(Cli, HelpListsSubcommands) {
  const RunResult r = run_omma("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* name : {"design", "coverage", "simulate", "stitch", "demo", "isp", "calibrate", "run"})
    EXPECT_NE(r.out.find(name), std::string::npos) << name;
}

TEST(Cli, UnknownSubcommandFails) {
  const RunResult r = run_omma("no-such-command");
  EXPECT_EQ(r.exit_code, 1);  // like every other error (CLI11's own code was 109)
  EXPECT_NE(r.err.find("omma: error:"), std::string::npos) << r.err;
}

TEST(Cli, RigCheckRejectsBadFiles) {
  const auto dir = temp_dir("rigcheck");
  std::ofstream(dir / "bad.json") << R"({"dome": {"radius_mm": 5}, "cameras": [{"id": 0}]})";
  const RunResult r = run_omma("rig check " + (dir / "bad.json").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("missing"), std::string::npos) << r.err;
  const RunResult missing = run_omma("rig check " + (dir / "none.json").string());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("does not exist"), std::string::npos) << missing.err;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace omma::test
