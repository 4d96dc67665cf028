#!/usr/bin/env bash
# The single-shot calibration table (docs/results/calibration_table.md): the calibration tests on
# the lake, the Louvre and the colon print the figures of each row (Ceres on one thread:
# reproducible). Needs the build's test programs (scripts/build.sh) and ../shared/data.
#   docs/results/calibration_table.sh           (BUILD=... for another build folder)
set -euo pipefail
cd "$(dirname "$0")/../.."
BUILD=${BUILD:-build}
"$BUILD/src/omma/calib/omma_calib_test" \
  --gtest_filter='Calibrate.FarFieldPhotoMeetsAccuracyTargets:Calibrate.FeaturelessSkyCamerasKeepNominalValuesWithWarning:Calibrate.ColonNearFieldCalibration'
