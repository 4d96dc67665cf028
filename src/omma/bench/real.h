// `omma real`: omma measured on real photographs with ground truth that no simulator made, beside
// the peers a user would otherwise pick (OpenCV, COLMAP, Hugin), every peer run in the same process
// or the same run. The photographs are OpenCV's samples (testing/real_data.h: Debian's opencv-doc).
//
// Every case returns one JSON object: what was measured for omma and for each peer (errors against
// the truth, in the units its key names: _deg, _px, _pct, _db; times in _s), the truth it was
// measured against, and the pictures it wrote under RealOptions::out_dir (paths relative to it).
// scripts/real_images.sh runs every case and writes docs/results/real_images.md from these objects.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace omma::bench {

struct RealOptions {
  std::filesystem::path data_dir;  // OpenCV's samples (testing::opencv_samples_dir() when empty)
  std::filesystem::path out_dir;   // pictures and intermediate files; a temporary folder when empty
  bool peers = true;               // also run the peers (OpenCV, COLMAP, Hugin) in the same run
  bool quick = false;              // the variant that fits a CI test's time
  int threads = 2;
};

// Calibration of the real stereo rig (left01..14 / right01..14) from its natural features, started
// from a focal length 3 % off and a pose 5 degrees off, against cv::stereoCalibrate on the
// chessboard of the same images; COLMAP's mapper on the same images beside it. (real_stereo.cc)
nlohmann::json real_stereo_calibration(const RealOptions& opt);

// The depth sweep on the rectified Middlebury Aloe pair as a two-camera rig, against its
// ground-truth disparity, beside OpenCV's StereoSGBM. (real_depth.cc)
nlohmann::json real_depth(const RealOptions& opt);

// A real pair ("leuven", "aero" or "graf") calibrated and stitched by omma, beside OpenCV's
// Stitcher and Hugin (cpfind, autooptimiser, nona). (real_stitch.cc)
nlohmann::json real_stitch(const std::string& pair, const RealOptions& opt);
std::vector<std::string> real_stitch_pairs();  // {"leuven", "aero", "graf"}

}  // namespace omma::bench
