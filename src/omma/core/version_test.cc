#include "omma/core/version.h"

#include <fstream>
#include <regex>
#include <string>

#include <gtest/gtest.h>

namespace omma {
namespace {

TEST(Version, IsTheVersionFile) {
  std::ifstream in(std::string(OMMA_SOURCE_DIR) + "/VERSION");
  std::string v;
  ASSERT_TRUE(std::getline(in, v));
  EXPECT_EQ(version(), v);
  EXPECT_TRUE(std::regex_match(version(), std::regex(R"(\d+\.\d+\.\d+)"))) << version();
}

}  // namespace
}  // namespace omma
