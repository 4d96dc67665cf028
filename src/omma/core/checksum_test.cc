#include "omma/core/checksum.h"

#include <cstring>
#include <string>

#include <gtest/gtest.h>

namespace omma {
namespace {

TEST(Checksum, Crc32MatchesTheStandardCheckValueAndChains) {
  const std::string s = "123456789";
  EXPECT_EQ(crc32(s.data(), s.size()), 0xCBF43926u);  // the CRC-32/ISO-HDLC check value
  EXPECT_EQ(crc32(s.data() + 4, 5, crc32(s.data(), 4)), 0xCBF43926u);
  EXPECT_EQ(crc32(nullptr, 0), 0u);
}

}  // namespace
}  // namespace omma
