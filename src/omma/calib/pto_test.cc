// PTO export/import: the convention mapping (pto.h) round-trips, and Hugin's nona renders our
// exported project like our own nearest-camera render (the real peer).
#include "omma/calib/pto.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <regex>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/calib/photometric.h"
#include "omma/calib/rig_diff.h"
#include "omma/core/frames.h"
#include "omma/core/srgb.h"
#include "omma/design/prototype.h"
#include "omma/isp/photometric.h"
#include "omma/pano/stitch.h"
#include "omma/sim/perturb.h"
#include "omma/testing/expect.h"
#include "omma/testing/test_scenes.h"

namespace omma::calib {
namespace {
namespace fs = std::filesystem;

std::string strip_omma_comments(const std::string& text) {
  return std::regex_replace(text, std::regex("#-omma[^\n]*\n"), "");
}

Rig perturbed_k1_rig() {
  // fu = fv, k1 only, shifted centres.
  return sim::perturb_rig_rms(testing::test_rig_24(), testing::kCalibrationErrors, 11);
}

// nona's output: its alpha channel (if any) is returned as the coverage mask and removed from
// `image`, which becomes BGR; without alpha every pixel counts as covered.
cv::Mat split_alpha(cv::Mat& image) {
  if (image.channels() != 4) return cv::Mat(image.size(), CV_8U, cv::Scalar(255));
  cv::Mat alpha;
  cv::extractChannel(image, alpha, 3);
  cv::cvtColor(image, image, cv::COLOR_BGRA2BGR);
  return alpha;
}

TEST(Pto, YawPitchRollConventions) {
  // y = p = r = 0 looks along dome -x with image right = +y, image down = -z.
  PtoCamera p;
  p.width = p.height = 250;
  p.hfov_deg = 64;
  RigCamera c = camera_from_pto(p);
  EXPECT_LT((c.frame.t - Vec3(-1, 0, 0)).norm(), 1e-12);
  EXPECT_LT((c.frame.u - Vec3(0, 1, 0)).norm(), 1e-12);
  EXPECT_LT((c.frame.v - Vec3(0, 0, -1)).norm(), 1e-12);
  p.yaw_deg = 90;  // turn right: towards +y
  EXPECT_LT((camera_from_pto(p).frame.t - Vec3(0, 1, 0)).norm(), 1e-12);
  p.yaw_deg = 0;
  p.pitch_deg = 90;  // look up: +z
  EXPECT_LT((camera_from_pto(p).frame.t - Vec3(0, 0, 1)).norm(), 1e-12);
  EXPECT_NEAR(camera_from_pto(p).in.fu, 125 / std::tan(deg2rad(32)), 1e-9);
}

TEST(Pto, RoundTripIsLosslessForWhatBothHold) {
  const Rig rig = perturbed_k1_rig();
  const PtoExportSummary ex = export_pto(rig);
  EXPECT_LT(ex.max_fit_px, 1e-6);  // k1 alone maps exactly onto PanoTools' b (and v)
  // Without omma's comment lines: only what PTO itself holds.
  const PtoImportSummary im = import_pto(strip_omma_comments(ex.text));
  ASSERT_EQ(im.rig.cameras.size(), rig.cameras.size());
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const auto& a = rig.cameras[i];
    const auto& b = im.rig.cameras[i];
    EXPECT_LT(angle_between(a.frame.t, b.frame.t), 1e-9);
    EXPECT_LT(angle_between(a.frame.u, b.frame.u), 1e-9);
    EXPECT_NEAR(a.in.fu, b.in.fu, 1e-6 * a.in.fu);
    EXPECT_NEAR(a.in.cu, b.in.cu, 1e-9);
    EXPECT_NEAR(a.in.cv, b.in.cv, 1e-9);
    EXPECT_NEAR(a.in.k[0], b.in.k[0], 1e-7);
    EXPECT_NEAR(b.in.k[1], 0, 1e-7);
    EXPECT_NEAR(b.in.k[4], 0, 1e-7);
  }
  // With the comment lines everything comes back (ids, positions, aov).
  const PtoImportSummary full = import_pto(ex.text);
  const RigDiff d = diff_rigs(full.rig, rig);
  EXPECT_LT(d.orientation_error_deg.max, 1e-7);
  EXPECT_LT(d.focal_error_rel.max, 1e-9);
  EXPECT_LT(d.center_error_px.max, 1e-9);
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    EXPECT_EQ(full.rig.cameras[i].id, rig.cameras[i].id);
    EXPECT_NEAR(full.rig.cameras[i].in.aov, rig.cameras[i].in.aov, 1e-12);
    EXPECT_LT((full.rig.cameras[i].position_mm - rig.cameras[i].position_mm).norm(), 1e-9);
  }
}

TEST(Pto, HigherRadialTermsAreFittedWithASmallResidual) {
  Rig rig = testing::test_rig_24();
  rig.cameras.resize(1);
  rig.cameras[0].in.k = {0.05, -0.02, 0, 0, 0.01};
  LensFit fit;
  const PtoCamera p = pto_from_camera(rig.cameras[0], &fit);
  std::printf(
      "k = (0.05, -0.02, k5 0.01): PTO fit residual rms %.4f px, max %.4f px (a %.5f b %.5f c %.5f v %.4f)\n",
      fit.rms_px, fit.max_px, p.a, p.b, p.c, p.hfov_deg);
  EXPECT_GT(fit.max_px, 1e-6);  // not exactly representable ...
  EXPECT_LT(fit.max_px, 0.5);   // ... but close over the image
  LensFit back;
  const RigCamera c = camera_from_pto(p, 3, &back);
  EXPECT_LT(back.max_px, 0.5);
  // The imported camera projects like the original to within the fit residuals.
  const CameraModel a = rig.cameras[0].model(), b = c.model();
  double worst = 0;
  for (double x = 5; x < 250; x += 20)
    for (double y = 5; y < 250; y += 20) {
      const Vec3 w = a.unproject({x, y});
      const Vec3 wb = rig.cameras[0].frame.t;  // same orientation mapping checked elsewhere
      (void)wb;
      const Vec2 pb = *b.project(Vec3(c.frame.dome_to_camera().transpose() * (a.frame.dome_to_camera() * w)));
      worst = std::max(worst, (pb - Vec2(x, y)).norm());
    }
  EXPECT_LT(worst, 1.0);
}

TEST(Pto, UnsupportedLensAndMissingImagesFail) {
  const std::string fisheye = "p f2 w100 h50 v360\ni w250 h250 f3 v120 y0 p0 r0 n\"cam_00.png\"\n";
  try {
    import_pto(fisheye);
    FAIL() << "fisheye accepted";
  } catch (const PtoError& e) {
    EXPECT_NE(std::string(e.what()).find("lens type f3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(import_pto("p f2 w100 h50 v360\n"), PtoError);
  EXPECT_THROW(import_pto("i f0 v60 y0 p0 r0 n\"/nonexistent/cam_00.png\"\n"),
               PtoError);  // no size, no image
  const PtoImportSummary warn = import_pto("i w250 h250 f0 v60 y0 p0 r0 n\"/nonexistent/cam_00.png\"\n");
  EXPECT_FALSE(warn.warnings.empty());
}

// Malformed numbers, bare image lines and truncated projects are refused, not imported as
// something else (y=nan as yaw 0, a bare 'i' line skipped, a cut project as 6 or 12 of 24 cameras).
TEST(Pto, MalformedAndTruncatedProjectsAreRefused) {
  const std::string line = "i w250 h250 f0 v60 y10 p20 r0 n\"cam_00.png\"\n";
  EXPECT_EQ(import_pto(line).rig.cameras.size(), 1u);
  auto refused = [](const std::string& text) {
    try {
      const PtoImportSummary r = import_pto(text);
      ADD_FAILURE() << "imported " << r.rig.cameras.size() << " cameras from:\n" << text;
    } catch (const PtoError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  for (const char* bad :
       {"y=nan", "ynan", "yinf", "y1e999", "y12abc", "y", "y=7", "w1e10", "w250.5", "h-3", "f1e300", "v"}) {
    std::string text = line;
    const std::string key(1, bad[0]);
    const size_t at = text.find(" " + key) + 1;
    text.replace(at, text.find(' ', at) - at, bad);
    EXPECT_FALSE(refused(text).empty()) << bad;
  }
  EXPECT_NE(refused(line + "i\n").find("line 2"), std::string::npos);
  EXPECT_NE(refused(line + "i \n" + line).find("line 2"), std::string::npos);
  // Cut anywhere, our export either imports every camera or is refused.
  const Rig rig = perturbed_k1_rig();
  const std::string text = export_pto(rig).text;
  const size_t last_line = text.rfind('\n', text.size() - 2) + 1;
  int refusals = 0;
  for (size_t cut = 1; cut <= text.size(); cut += (cut < last_line ? 7 : 1)) {
    try {
      EXPECT_EQ(import_pto(text.substr(0, cut)).rig.cameras.size(), rig.cameras.size()) << "cut at " << cut;
    } catch (const PtoError&) {
      ++refusals;
      EXPECT_LT(cut + 1, text.size()) << "the whole project was refused";
    }
  }
  EXPECT_GT(refusals, 100);
  // Without omma's comment lines (a project written by Hugin), a cut inside an image line is found;
  // a cut exactly between two image lines cannot be told from a smaller project.
  const std::string hugin = strip_omma_comments(text);
  for (size_t cut = hugin.find("\ni ") + 2; cut + 1 < hugin.size(); cut += 5)
    if (hugin[cut - 1] != '\n' && hugin.substr(cut - 1, 2) != "\"\n") {
      const std::string part = hugin.substr(0, cut);
      EXPECT_THROW(import_pto(part), PtoError)
          << "cut at " << cut << ": ..." << part.substr(part.size() - 30);
    }
}

// The real peer: nona renders our exported project; its panorama, as it is (no flip: both are the
// world the right way round, conventions.h (G1), pto.h), agrees with the reference stitcher's
// nearest-neighbour panorama (omma stitch --method nn) on the covered region, and its mirror image
// does not (so the test tells the two handednesses apart). Frames: the small far-field renderer of
// testing/test_scenes.h with a perturbed rig (shifted centres, k1, focal, rotations) so that every
// converted parameter matters.
TEST(Pto, NonaRendersOurExportLikeOurNearestNeighbourStitch) {
  if (std::system("which nona >/dev/null 2>&1") != 0) GTEST_SKIP() << "nona (hugin-tools) not installed";
  const cv::Mat scene = testing::load_photo(std::string(OMMA_DATA_DIR) + "/lake.jpg");
  ASSERT_FALSE(scene.empty());
  const Rig rig = perturbed_k1_rig();
  const auto frames = testing::render_photo_frames(rig, scene);
  const fs::path dir = fs::temp_directory_path() / ("omma-pto-nona-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  for (size_t i = 0; i < frames.size(); ++i)
    cv::imwrite((dir / frame_filename(rig.cameras[i].id)).string(), frames[i]);
  PtoExportOptions opt;
  opt.pano_width = 1440;
  opt.interpolator = 5;  // bilinear, like our sampler
  const PtoExportSummary ex = export_pto(rig, opt);
  std::ofstream(dir / "rig.pto") << ex.text;
  const std::string cmd = "cd " + dir.string() + " && nona -m PNG -o nona_out rig.pto >nona.log 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << "nona failed, see " << (dir / "nona.log");
  cv::Mat nona = cv::imread((dir / "nona_out.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(nona.empty());
  std::printf("nona output %dx%d, %d channels\n", nona.cols, nona.rows, nona.channels());
  ASSERT_EQ(nona.cols, 1440);
  ASSERT_EQ(nona.rows, 360);
  cv::Mat nona_mask = split_alpha(nona);
  const PanoGrid grid{Projection::kEquirect, 1440, 360};
  pano::StitchOptions so;  // what `omma stitch --method nn` does
  so.method = pano::Method::kNearest;
  so.grid = grid;
  so.progress = false;
  const cv::Mat ours = to_u8(pano::stitch(rig, frames, so));
  cv::Mat mask;
  cv::cvtColor(ours, mask, cv::COLOR_BGR2GRAY);
  mask = mask > 0;
  cv::Mat both;
  cv::bitwise_and(mask, nona_mask > 0, both);
  const double covered = cv::countNonZero(both) / double(both.total());
  const double db = testing::psnr_masked(ours, nona, both);
  std::printf("nona vs omma stitch nn: PSNR %.2f dB over %.1f %% of the panorama\n", db, 100 * covered);
  const cv::Mat truth = testing::render_photo_truth(scene, grid);
  std::printf("vs truth: nona %.2f dB, ours %.2f dB\n", testing::psnr_masked(nona, truth, both),
              testing::psnr_masked(ours, truth, both));
  cv::Mat nona_flipped, mask_flipped, both_flipped;
  cv::flip(nona, nona_flipped, 1);
  cv::flip(nona_mask, mask_flipped, 1);
  cv::bitwise_and(mask, mask_flipped > 0, both_flipped);
  const double db_flipped = testing::psnr_masked(ours, nona_flipped, both_flipped);
  std::printf("nona flipped left-right vs omma stitch nn: PSNR %.2f dB\n", db_flipped);
  EXPECT_GT(covered, 0.5);
  EXPECT_GE(db, 35.0);  // nona's interpolation differs from ours: 35-41 dB, never a flip's ~16 dB
  EXPECT_LT(db_flipped, db - 10);
  fs::remove_all(dir);
}

// A photometric model per camera (core/photometric.h): vignetting with shifted centres and colour
// gains, as Hugin would hold them.
Rig with_photometric(Rig rig) {
  cv::RNG rng(17);
  for (RigCamera& c : rig.cameras) {
    Photometric p;
    p.vignetting = {rng.uniform(-0.55, -0.35), rng.uniform(0.0, 0.15), rng.uniform(-0.08, 0.0)};
    p.center_px = Vec2(rng.uniform(-6.0, 6.0), rng.uniform(-6.0, 6.0));
    p.gains = {rng.uniform(0.85, 1.15), rng.uniform(0.85, 1.15), rng.uniform(0.85, 1.15)};
    c.photometric = p;
  }
  return rig;
}

TEST(Pto, PhotometricModelRoundTripsUnderHuginsNames) {
  const Rig rig = with_photometric(perturbed_k1_rig());
  const std::string text = export_pto(rig).text;
  // Hugin's names carry it: Eev, Er, Eb, Vb, Vc, Vd, Vx, Vy with Vm5.
  const Photometric& p0 = *rig.cameras[0].photometric;
  EXPECT_NE(text.find(fmt::format(" Vb{:.12g} ", p0.vignetting[0])), std::string::npos);
  EXPECT_NE(text.find(fmt::format(" Eev{:.12g} ", -std::log2(p0.gains[1]))), std::string::npos);
  // Import (without our comment lines: from the PTO's own fields alone).
  const PtoImportSummary back = import_pto(strip_omma_comments(text));
  ASSERT_EQ(back.rig.cameras.size(), rig.cameras.size());
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    ASSERT_TRUE(back.rig.cameras[i].photometric.has_value());
    const Photometric& a = *rig.cameras[i].photometric;
    const Photometric& b = *back.rig.cameras[i].photometric;
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(a.vignetting[k], b.vignetting[k], 1e-9);
      EXPECT_NEAR(a.gains[k] / b.gains[k], 1, 1e-9);
    }
    EXPECT_NEAR((a.center_px - b.center_px).norm(), 0, 1e-9);
  }
  // No model: the neutral values, and none on import.
  const std::string plain = export_pto(perturbed_k1_rig()).text;
  EXPECT_NE(plain.find(" Eev0 Er1 Eb1 "), std::string::npos);
  EXPECT_FALSE(import_pto(plain).rig.cameras[0].photometric.has_value());
  // Va scales the model (folded into the gains); a non-positive Va or a falloff that reaches zero
  // is an error.
  const PtoImportSummary va =
      import_pto("i w250 h250 f0 v60 y0 p0 r0 Va2 Vb-0.4 Vm5 Eev0 Er1 Eb1 n\"x.png\"\n");
  ASSERT_TRUE(va.rig.cameras[0].photometric.has_value());
  EXPECT_NEAR(va.rig.cameras[0].photometric->vignetting[0], -0.2, 1e-12);
  EXPECT_NEAR(va.rig.cameras[0].photometric->gains[1], 2, 1e-12);
  EXPECT_THROW(import_pto("i w250 h250 f0 v60 y0 p0 r0 Va1 Vb-1.5 Vm5 n\"x.png\"\n"), PtoError);
  EXPECT_THROW(import_pto("i w250 h250 f0 v60 y0 p0 r0 Va0 Vb-0.4 Vm5 n\"x.png\"\n"), PtoError);
  // Found by the fuzzer: a vignetting mode beyond int (UB when narrowed) or not whole.
  EXPECT_THROW(
      import_pto(
          "i w250 h250 f0 v60 y0 p0 r0 Vm57777777777777777777777777777777777777777777777 n\"x.png\"\n"),
      PtoError);
  EXPECT_THROW(import_pto("i w250 h250 f0 v60 y0 p0 r0 Vm1.5 Vb-0.4 n\"x.png\"\n"), PtoError);
}

// The real peer with photometric correction: frames darkened and tinted by each camera's model,
// written in linear light (16-bit) and exported with Rt1 (linear response), so that nona divides
// by Hugin's V * 2^-Eev (and Er, Eb) exactly as we do; nona's panorama, encoded to sRGB, against our
// nearest-neighbour stitch of the corrected frames (isp/photometric.h). Measured: 37.4 dB (32.2 dB
// against the uncorrected frames' stitch; the geometry-only test above: 40.7 dB; nona interpolates
// in linear light, we in sRGB).
TEST(Pto, NonaAppliesOurPhotometricModelLikeWeDo) {
  if (std::system("which nona >/dev/null 2>&1") != 0) GTEST_SKIP() << "nona (hugin-tools) not installed";
  const cv::Mat scene = testing::load_photo(std::string(OMMA_DATA_DIR) + "/lake.jpg");
  ASSERT_FALSE(scene.empty());
  const Rig rig = with_photometric(perturbed_k1_rig());
  const auto clean = testing::render_photo_frames(rig, scene);
  const fs::path dir = fs::temp_directory_path() / ("omma-pto-nona-ph-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::vector<cv::Mat> frames;  // what the cameras give: sRGB 8-bit through their model
  for (size_t i = 0; i < clean.size(); ++i) {
    const RigCamera& c = rig.cameras[i];
    const Photometric& p = *c.photometric;
    cv::Mat lin = decode_linear(clean[i]), f8(lin.size(), CV_8UC3), f16(lin.size(), CV_16UC3);
    for (int r = 0; r < lin.rows; ++r)
      for (int col = 0; col < lin.cols; ++col)
        for (int k = 0; k < 3; ++k) {
          const double v =
              std::min(1.0, lin.at<cv::Vec3f>(r, col)[k] * p.gains[k] *
                                vignetting_falloff(p, c.in.width, c.in.height, col + 0.5, r + 0.5));
          f8.at<cv::Vec3b>(r, col)[k] =
              cv::saturate_cast<uint8_t>(std::lround(255 * linear_to_srgb(float(v))));
        }
    frames.push_back(f8);
    // nona's input: the same frame in linear light, 16 bits.
    decode_linear(f8).convertTo(f16, CV_16UC3, 65535.0);
    cv::imwrite((dir / frame_filename(c.id)).string(), f16);
  }
  PtoExportOptions opt;
  opt.pano_width = 1440;
  opt.interpolator = 5;
  opt.linear_response = true;
  std::ofstream(dir / "rig.pto") << export_pto(rig, opt).text;
  const std::string cmd = "cd " + dir.string() + " && nona -m PNG -o nona_out rig.pto >nona.log 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << "nona failed, see " << (dir / "nona.log");
  cv::Mat nona = cv::imread((dir / "nona_out.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(nona.empty());
  ASSERT_EQ(nona.depth(), CV_16U);
  cv::Mat nona_mask = split_alpha(nona);  // as it is: no flip (pto.h)
  // Linear 16-bit -> sRGB 8-bit.
  cv::Mat nona8(nona.size(), CV_8UC3);
  for (int r = 0; r < nona.rows; ++r)
    for (int c = 0; c < nona.cols * 3; ++c)
      nona8.ptr<uint8_t>(r)[c] =
          cv::saturate_cast<uint8_t>(std::lround(255 * linear_to_srgb(nona.ptr<uint16_t>(r)[c] / 65535.0f)));
  const PanoGrid grid{Projection::kEquirect, 1440, 360};
  pano::StitchOptions so;
  so.method = pano::Method::kNearest;
  so.grid = grid;
  so.progress = false;
  const cv::Mat ours = to_u8(pano::stitch(rig, isp::correct_frames(rig, frames), so));
  const cv::Mat uncorrected = to_u8(pano::stitch(rig, frames, so));
  cv::Mat mask;
  cv::cvtColor(ours, mask, cv::COLOR_BGR2GRAY);
  mask = mask > 0;
  cv::Mat both;
  cv::bitwise_and(mask, nona_mask > 0, both);
  const double db = testing::psnr_masked(ours, nona8, both);
  const double db_uncorrected = testing::psnr_masked(uncorrected, nona8, both);
  std::printf(
      "nona (photometric, linear response) vs omma corrected nn: %.2f dB (uncorrected frames: %.2f dB) over "
      "%.1f %%\n",
      db, db_uncorrected, 100.0 * cv::countNonZero(both) / double(both.total()));
  EXPECT_GE(db, 30.0);
  EXPECT_GT(db, db_uncorrected + 3);  // the correction is what agrees, not the geometry alone
  fs::remove_all(dir);
}

using testing::refusal;

TEST(Options, PtoExportOptionsRefuseBadValues) {
  PtoExportOptions o;
  EXPECT_TRUE(o.IsValid());
  o.pano_width = 1;
  EXPECT_FALSE(o.IsValid());
  EXPECT_NE(refusal([&] { export_pto(design::thesis_prototype_rig(), o); }).find("pano_width"),
            std::string::npos);
}

}  // namespace
}  // namespace omma::calib
