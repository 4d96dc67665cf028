// Geometric calibration, stage 3 of calibrate.h: subpixel refinement of the feature tracks after a
// first bundle adjustment, by ECC alignment of image patches (subpixel.h) started from the current
// model's homography of the local scene plane (the study behind the near-field choices:
// docs/near_field_calibration.md).
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "omma/calib/bundle.h"
#include "omma/calib/calibrate.h"
#include "omma/calib/subpixel.h"

namespace omma::calib {

// Subpixel refinement (subpixel.h) after a solve. Every track: the observation nearest its
// camera's principal point is the reference; every other observation is replaced by the ECC
// alignment of the reference's patch, started from the current model's homography of the local
// scene plane. The plane at a near-field point is normal to the smallest principal axis of its
// nearest neighbouring scene points (the direction to the dome centre when those are degenerate);
// in the far field it is the plane at infinity. Observations whose alignment fails are dropped.
std::vector<std::vector<TrackObservation>> refine_tracks(const Rig& rig, const std::vector<cv::Mat>& gray,
                                                         const SolveState& st, bool near,
                                                         const SubpixelOptions& so, int* attempted,
                                                         int* refined);

// Dense guided correspondences (near field, after the first solve). Every keypoint of every camera
// is a candidate reference pixel, not only the matched ones: its depth is the median depth of the
// current solution's scene points observed nearest to it in the same camera, its plane normal comes
// from their 3D neighbours, and the current model predicts where it lies in every other camera.
// A candidate is used in the one camera (of those that see it) where it lies nearest the principal
// point, so that one region of the wall is one reference patch; every other camera that sees it
// is a target of the ECC alignment (subpixel.h), started from the plane homography. Each aligned
// observation gets the whitening of its covariance (AlignInfo), scaled so that the median
// observation weighs 1, floored at dense_weight_floor (CalibrationOptions) times the median sigma.
std::vector<std::vector<TrackObservation>> dense_tracks(const Rig& rig, const std::vector<cv::Mat>& gray,
                                                        const std::vector<CameraFeatures>& feats,
                                                        const SolveState& st, const CalibrationOptions& opt,
                                                        int* attempted, int* refined);

}  // namespace omma::calib
