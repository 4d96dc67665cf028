// Real photographs with ground truth for tests and benchmarks: the sample data of Debian's
// opencv-doc package (installed by scripts/install-deps.sh --test), never downloaded at run time.
//
//   left01..14.jpg, right01..14.jpg   a real stereo pair (640 x 480, gray), a chessboard held in an
//                                     office (9 x 6 inner corners); left10 / right10 are missing
//   intrinsics.yml                    an OpenCV camera calibration file (camera matrix, distortion)
//   aloeL.jpg, aloeR.jpg, aloeGT.png  the Middlebury Aloe pair (rectified) and its disparity truth
//   leuvenA.jpg, leuvenB.jpg          a street pair; its camera matrix in essential_mat_data.txt
//   aero1.jpg, aero3.jpg              an aerial pair
//   graf1.png, graf3.png, H1to3p.xml  the Graffiti pair and the homography between them
#pragma once

#include <filesystem>

namespace omma::testing {

// The folder of OpenCV's sample images: $OMMA_OPENCV_SAMPLES if set, else
// /usr/share/doc/opencv-doc/examples/data. Empty path if it does not hold aloeL.jpg.
std::filesystem::path opencv_samples_dir();

}  // namespace omma::testing
