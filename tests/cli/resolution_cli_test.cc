// CLI tests of `omma resolution` (thesis §5.5.2 in simulation).
#include <gtest/gtest.h>

#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {

TEST(ResolutionCli, PrototypeResolvesAboutHalfADegree) {
  const RunResult r = run_omma("resolution --size 720x720 --supersample 2 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  ASSERT_TRUE(j["limit"].is_object()) << j.dump();
  const double bar = j["limit"]["bar_deg"], cam_px = j["camera_deg_per_px"];
  // The limit lies between one and four camera pixels per bar (Nyquist is two per line pair = one
  // per bar; the optical blur and the stitch cost some); thesis: 0.5 deg (group 1 element 2).
  EXPECT_GE(bar, 1.0 * cam_px);
  EXPECT_LE(bar, 4.0 * cam_px);
  EXPECT_EQ(j["elements"].size(), 30u);
  // The ground truth on the same grid resolves at least as fine.
  EXPECT_LE(j["truth_limit"]["bar_deg_from_centre"].get<double>(),
            j["limit"]["bar_deg_from_centre"].get<double>());
}

TEST(ResolutionCli, BadInput) {
  const RunResult m = run_omma("resolution --method blur");
  EXPECT_EQ(m.exit_code, 1);
  EXPECT_NE(m.err.find("blur"), std::string::npos) << m.err;
  const RunResult s = run_omma("resolution --size 12");
  EXPECT_EQ(s.exit_code, 1);
  EXPECT_NE(s.err.find("WxH"), std::string::npos) << s.err;
}

}  // namespace
}  // namespace omma::test
