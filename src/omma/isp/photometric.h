// Photometric correction of camera frames: divides a frame's LINEAR signal by the
// camera's gain_c * V(px) (the model of core/photometric.h), i.e. for an sRGB-encoded frame
//   out = encode( decode(in) / (gain_c * V(px)) ),   clipped to [0, 1].
// The readable reference works in double precision; the fast path is the engine's: per camera a
// gain map 1/V per pixel and per channel a decode table with 1/gain_c folded in (PhotometricTable),
// applied when a frame enters the frame store. Both are tested against each other.
// For raw Bayer frames the model becomes the ISP's flat-field gain map (flat_gain_from_model).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/photometric.h"
#include "omma/core/rig.h"
#include "omma/isp/isp.h"

namespace omma::isp {

// Reference: CV_8UC3 (sRGB) or CV_16UC3 (sRGB, 16-bit) frame of a width x height camera ->
// corrected frame of the same type. Throws std::invalid_argument on another type or size.
cv::Mat correct_photometric_reference(const cv::Mat& frame, const Photometric& p);

// The fast path for 8-bit sRGB frames of one camera.
//   gain map:  Q4.12 (4096 = 1.0) per pixel, 1 / V(px) rounded, saturated at 65535 (exact for
//              V >= 1/16);
//   decode:    per channel 256 entries, linear / gain_c in Q16.16 (65536 = full scale), rounded;
//   product:   64-bit decode * gain map (Q.28), + 2^13 and >> 14 = linear in Q0.14 rounded to the
//              nearest, clamped to 2^14 (full scale: the output clips there);
//   encode:    2^14 + 1 entries: sRGB 8-bit of linear i / 2^14, rounded.
// The encode table's step (1/16384 of full scale, 0.2 of an 8-bit step at black, where sRGB is
// steepest) and the gain map's rounding keep the result within one 8-bit step of the reference (test).
class PhotometricTable {
 public:
  static constexpr int kEncodeBits = 14;  // encode table: 2^14 + 1 entries over [0, 1]
  PhotometricTable() = default;
  PhotometricTable(const Photometric& p, int width, int height);
  bool empty() const { return width_ == 0; }
  int width() const { return width_; }
  int height() const { return height_; }
  // in: CV_8UC3 width x height (continuous or not); out is (re)allocated CV_8UC3. in == out allowed.
  void apply(const cv::Mat& in, cv::Mat& out) const;
  // The same, writing one pixel row: src and dst hold width * 3 bytes (BGR) of row `row`.
  void apply_row(const uint8_t* src, uint8_t* dst, int row) const;

 private:
  int width_ = 0, height_ = 0;
  std::vector<uint16_t> gain_q12_;               // width * height, 1 / V in Q4.12
  std::array<std::vector<uint32_t>, 3> decode_;  // per channel (B, G, R): 256 entries, Q0.16 / gain_c
  std::vector<uint8_t> encode_;                  // 2^kEncodeBits + 1 entries
};

// One table per camera of the rig (empty tables for cameras without a photometric model, or for
// every camera when `enabled` is false).
std::vector<PhotometricTable> photometric_tables(const Rig& rig, bool enabled = true);

// Corrects every frame (CV_8UC3 sRGB, rig order) of the cameras that have a photometric model,
// in parallel; frames of other cameras are returned unchanged (shared, not copied).
std::vector<cv::Mat> correct_frames(const Rig& rig, const std::vector<cv::Mat>& frames);

// The model as the ISP's flat-field gain map (IspOptions::flat_gain, Q12 per raw pixel of an RGGB
// mosaic): 1 / (gain_c * V(px)) with c the CFA colour of the raw pixel, clamped to [0, 65535].
// With it, develop() needs no white balance (Awb::kNone): the gains are the model's.
cv::Mat flat_gain_from_model(const Photometric& p, int width, int height);

// Raw frames (rig order) developed with the rig's photometric model: a camera with a model gets its
// flat_gain_from_model() and no white balance (its gains are the model's), a camera without one the
// options as given. `gains` (flat_gains_from_rig) may be computed once for many frame sets. Empty
// raw frames stay empty (a camera missing from a frame set). In parallel over the frames.
std::vector<cv::Mat> flat_gains_from_rig(const Rig& rig);  // empty Mats for cameras without a model
std::vector<cv::Mat> develop_with_model(const std::vector<cv::Mat>& raws, const IspOptions& options,
                                        const std::vector<cv::Mat>& gains);

}  // namespace omma::isp
