// The recording planner against Table 7.1 and the text of §7.1 (../shared/notes/gigaeye-spec.md §3).
#include "omma/design/recording_plan.h"

#include <cmath>

#include <gtest/gtest.h>

namespace omma::design {
namespace {

TEST(RecordingPlan, Table71Rows1To7ReproduceRow8IsFlagged) {
  const auto rows = check_table71();
  ASSERT_EQ(rows.size(), 8u);
  const double bw[] = {100.914, 68.477, 54.061, 54.061, 54.061, 36.041, 16.018, 33.750};
  const double mem[] = {177.388, 56.173, 95.029, 95.029, 53.850, 63.353, 28.157, 59.326};
  for (size_t i = 0; i < 8; ++i) {
    EXPECT_NEAR(rows[i].plan.camera_mib_per_s, bw[i], 5e-4) << i + 1;
    EXPECT_NEAR(rows[i].plan.camera_gib, mem[i], 5e-4) << i + 1;
    if (i < 7) {
      EXPECT_TRUE(rows[i].matches) << "row " << i + 1;
      EXPECT_FALSE(rows[i].fits_bits.has_value());
    }
  }
  // Row 8 prints 23 MB/s and 40 GB: that is 8 bits per pixel (22.5 -> 23 rounded half up), not 12.
  EXPECT_FALSE(rows[7].matches);
  ASSERT_TRUE(rows[7].fits_bits.has_value());
  EXPECT_EQ(*rows[7].fits_bits, 8);
  EXPECT_EQ(round_half_up(22.5), 23);
  EXPECT_DOUBLE_EQ(rows[0].plan.camera_bytes_per_s, 105815808.0);
}

TEST(RecordingPlan, FiveTerabytesForFortyFourCamerasIsWrong) {
  // L6537-6539: option 1 (30 min) "for 44 cameras 5.2 TB". 44 x 177.39 GiB = 7.62 TiB; 5.2 fits 30.
  RecordingPlanInput in = plan_input(table71()[0]);
  in.cameras = 44;
  const RecordingPlan p = make_plan(in);
  EXPECT_NEAR(p.rig_bytes / std::pow(2.0, 40), 7.62, 0.005);
  EXPECT_NEAR(p.rig_bytes / 1e12, 8.38, 0.005);
  in.cameras = 30;
  EXPECT_NEAR(make_plan(in).rig_bytes / std::pow(2.0, 40), 5.197, 0.001);
}

TEST(RecordingPlan, ConstraintsOfTheThesisSystem) {
  // Two cameras per 128 GB SATA-2 SSD (~150 MB/s), clock < 80 MHz.
  std::vector<int> hold;
  for (const Table71Row& row : table71()) {
    const RecordingPlan p = make_plan(plan_input(row));
    bool clock_ok = p.checks[0].ok, rate_ok = p.checks[2].ok;
    EXPECT_TRUE(p.checks[1].ok) << row.option;  // every clock can read its pixels
    if (clock_ok && rate_ok) hold.push_back(row.option);
    if (row.option == 1) {
      EXPECT_FALSE(rate_ok);  // 2 x 101 MiB/s = 211.6 MB/s > 150
    }
  }
  EXPECT_EQ(hold, (std::vector<int>{2, 4, 5, 6, 7, 8}));
  // Recording time per SSD: 14.86 min at full resolution (thesis 14), 18.8 at half (thesis 17).
  EXPECT_NEAR(make_plan(plan_input(table71()[1])).max_minutes, 14.86, 0.01);
  EXPECT_NEAR(make_plan(plan_input(table71()[4])).max_minutes, 18.82, 0.01);
  // Option 5's 17 minutes fit; 30 minutes (option 4) do not: device-capacity names it.
  EXPECT_TRUE(make_plan(plan_input(table71()[4])).feasible());
  const RecordingPlan p4 = make_plan(plan_input(table71()[3]));
  EXPECT_FALSE(p4.feasible());
  EXPECT_NE(p4.failed().find("device-capacity"), std::string::npos);
  EXPECT_EQ(p4.failed().find("device-write-rate"), std::string::npos);
}

TEST(RecordingPlan, ParsesUnitsAndRejectsBadInput) {
  EXPECT_DOUBLE_EQ(parse_bytes("128GB"), 128e9);
  EXPECT_DOUBLE_EQ(parse_bytes("128 GiB"), 128.0 * (1 << 30));
  EXPECT_DOUBLE_EQ(parse_bytes("150MB/s"), 150e6);
  EXPECT_DOUBLE_EQ(parse_bytes("2e3"), 2000);
  for (const char* bad : {"", "GB", "-1GB", "12 parsecs", "nan"})
    EXPECT_THROW(parse_bytes(bad), std::invalid_argument) << bad;
  RecordingPlanInput in;
  in.cameras_per_device = 0;
  EXPECT_THROW(make_plan(in), std::invalid_argument);
  in = {};
  in.bits = 17;
  EXPECT_THROW(make_plan(in), std::invalid_argument);
}

}  // namespace
}  // namespace omma::design
