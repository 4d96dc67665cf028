// `omma real depth` and `omma real stereo-calib` as a user runs them (the library's own tests hold
// the numbers: pano/stereo_real_test.cc, calib/stereo_real_test.cc), and bad input of `omma real`.
#include <filesystem>

#include <gtest/gtest.h>

#include "omma/testing/real_data.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;

// The quick variant (the Aloe pair at a quarter size, 321x278): measured omma 11.9 % bad-2 against
// SGBM's 14.3 %, median 0.27 px; the pictures a person looks at are written.
TEST(RealCli, DepthQuickBeatsSgbmAndWritesPictures) {
  if (testing::opencv_samples_dir().empty()) GTEST_SKIP() << "opencv-doc samples not installed";
  const fs::path out = temp_dir("real_depth");
  const RunResult r = run_omma("real depth --quick --json --out " + out.string(), 120);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = r.json();
  const double omma = j.at("omma").at("bad2_pct").get<double>();
  const double sgbm = j.at("sgbm").at("bad2_pct").get<double>();
  EXPECT_LE(omma, sgbm);
  EXPECT_LT(omma, 13.5);
  EXPECT_LT(j.at("omma").at("median_err_px").get<double>(), 0.35);
  int pictures = 0;
  for (const auto& e : fs::directory_iterator(out))
    if (e.path().extension() == ".png" && fs::file_size(e.path()) > 1000) ++pictures;
  EXPECT_GE(pictures, 5);  // disparity of truth, omma and SGBM; error maps of omma and SGBM
  fs::remove_all(out);
}

TEST(RealCli, BadInputSaysWhatIsWrong) {
  const fs::path empty = temp_dir("real_bad");
  RunResult r = run_omma("real depth --data " + (empty / "missing").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("omma: error:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("missing"), std::string::npos) << r.err;
  r = run_omma("real stitch nowhere");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("nowhere"), std::string::npos) << r.err;
  r = run_omma("real stereo-calib --data " + empty.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("omma: error:"), std::string::npos) << r.err;
  fs::remove_all(empty);
}

}  // namespace
}  // namespace omma::test
