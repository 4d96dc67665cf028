// Synthetic-aperture refocusing: the camera array as one large lens (Levoy et al., "Light field
// rendering", 1996; Vaish et al., "Using plane + parallax for calibrating dense camera arrays", 2004:
// the Stanford camera array). The thesis names it as what the overlap of Giga-Eye's cameras enables
// (§7.3: "light field based image processing applications such as refocusing and 3D rendering").
//
// Every output direction w (grid.h) from the observer q meets the FOCAL SURFACE at the distance
// F(w) (a sphere F = focus_mm around q, or a depth map) in the point X = q + F w. Every camera i
// that sees X (eq. 2.3 on its own ray X - c_i, contributors.h) is sampled there (eq. 5.21-5.26,
// bilinear) and the samples are averaged with the APERTURE weight
//     a_i = exp(-r_i^2 / (2 A^2))   (Gaussian; box: a_i = 1 if r_i <= A, else 0)
// where r_i is camera i's distance from the observer's ray (eq. 2.5, mm, contributors.h): the
// position of camera i's viewpoint in the synthetic lens's aperture plane. A = aperture_mm: +infinity
// gives every camera that sees X the same weight (the widest aperture the rig has); A -> 0 keeps
// only the camera nearest the ray (a pinhole: nn blending, everything as sharp as one camera).
// A feather e_i in [0, 1] (0 at camera i's image edge, 1 from `feather` of the image's smaller side
// inwards) multiplies a_i so that no image border shows as a step.
//
// What it does to the scene. A point at distance Z along w is seen by camera i displaced from the
// focal surface's point by the angle r_i |1/Z - 1/F| (small angles; the parallax of eq. 2.5's
// offset). Points ON the surface (Z = F) land on the same pixel in every camera: sharp. Points off
// it land r_i |1/Z - 1/F| apart in the cameras: the average spreads them over that angle (with the
// few cameras of a dome or Giga-Eye, as a few weaker copies rather than a smooth disc), so the blur
// grows with |1/Z - 1/F|, the distance from the surface in inverse depth, and with the aperture. A
// thin occluder in front of the surface covers different parts of the surface in different cameras;
// where at least one camera sees past it, the mean dilutes it by that camera's weight share, and the
// MEDIAN combination (below) removes it wherever the unoccluded cameras are the majority.
//
// Combinations: kMean, the weighted mean above (the classic synthetic aperture); kMedian, a
// consensus: the weighted median of the samples' gray levels (BT.601 luma) picks the majority, and
// the output is the weighted mean of the samples within consensus_gray of it (Vaish et al. 2006,
// "Reconstructing occluded surfaces using synthetic apertures", use medians and entropy for the
// same purpose). With two cameras the median of two is their mean.
//
// Images: frames as stitch.h (8U/16U/32F, 1 or 3 channels); the output CV_32FC3 BGR [0,1],
// grid-sized, black where no camera sees the surface point.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/grid.h"
#include "omma/core/rig.h"
#include "omma/pano/contributors.h"

namespace omma::pano {

enum class ApertureShape { kGaussian, kBox };
enum class RefocusCombine { kMean, kMedian };
ApertureShape parse_aperture_shape(const std::string& name);    // "gaussian" | "box"
RefocusCombine parse_refocus_combine(const std::string& name);  // "mean" | "median"
std::string to_string(ApertureShape s);
std::string to_string(RefocusCombine c);

struct RefocusOptions {
  PanoGrid grid;
  // The focal surface: a sphere of radius focus_mm around q (> 0; +infinity: the thesis's scene at
  // infinity), unless focus_depth is given: CV_32FC1 of the grid's size, mm from q (surface.h),
  // e.g. an estimated depth map (everything in focus).
  double focus_mm = 1000;
  cv::Mat focus_depth;
  // The synthetic aperture's radius A, mm (>= 0; +infinity: every camera alike), and its shape.
  double aperture_mm = std::numeric_limits<double>::infinity();
  ApertureShape shape = ApertureShape::kGaussian;
  RefocusCombine combine = RefocusCombine::kMean;
  double consensus_gray = 0.1;  // kMedian: samples within this gray level of the median, [0, 1]
  double feather = 0.05;        // fraction of the image's smaller side, [0, 0.5]
  SearchOptions search;         // the observer q
  bool progress = true;
  bool IsValid(std::string* why = nullptr) const;
};

struct RefocusSummary {
  cv::Mat image;        // CV_32FC3 BGR [0,1]
  cv::Mat cameras;      // CV_8UC1: cameras with a non-zero weight per pixel (the aperture's samples)
  double mean_cameras;  // over the pixels seen by at least one camera
};

// Throws std::invalid_argument on invalid options, frames (check_frames) or focus_depth.
RefocusSummary refocus(const Rig& rig, const std::vector<cv::Mat>& frames, const RefocusOptions& options);

// The 10-90 % rise distance (pixels) of the one straight step edge inside `roi` of `image` (any
// type, 1 or 3 channels; measured on the gray level): the slanted-edge method of ISO 12233 in its
// plainest form. The edge may be at any angle within 45 deg of vertical (or of horizontal: the
// image is transposed when the gradients say so); its position in every row is the centroid of the
// row's absolute gradient, a line is fitted through those, every pixel is binned by its distance
// from the line at 1/4 pixel, and the binned edge spread function's 10 % and 90 % crossings
// between its two plateaus (the means of its outer quarters) give the width. Smaller is sharper
// (about 1-2 px for a sharp edge resampled bilinearly). Returns NaN where the roi holds no edge
// (contrast below 0.05 of full scale). Throws std::invalid_argument if roi is not inside the image
// or smaller than 8 x 8.
double edge_width_10_90(const cv::Mat& image, const cv::Rect& roi);

// Sharpness against the truth by distance from the focal surface, for scenes without edge targets
// (the colon): the pixels are binned by their defocus |1/Z - 1/F| (1/mm; Z the true depth of the
// pixel, F the focus; +infinity depths count as 1/Z = 0) at the bin edges `edges` (ascending, the
// last bin open), and per bin the ratio of the image's gradient energy to the truth's, sum |grad
// image|^2 / sum |grad truth|^2 (gray levels, central differences, on the pixels of the bin where
// the truth has texture and `mask` (optional CV_8UC1, e.g. RefocusSummary::cameras >= 2: where the
// aperture holds two cameras or more) is non-zero): 1 = as sharp as the truth, less = blurred.
struct DefocusBin {
  double from = 0, to = 0;  // defocus range, 1/mm
  long pixels = 0;
  double energy_ratio = 0;  // NaN for an empty bin
};
std::vector<DefocusBin> sharpness_by_defocus(const cv::Mat& image, const cv::Mat& truth,
                                             const cv::Mat& depth_mm, double focus_mm,
                                             const std::vector<double>& edges, const cv::Mat& mask = {});

}  // namespace omma::pano
