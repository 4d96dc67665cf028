// The panorama shows the world the right way round (core/conventions.h (G1), (G2)), decided by
// judges that know nothing of omma's conventions:
//   * SIFT (OpenCV): a camera frame and the panorama match as they are, through a homography that
//     keeps orientation (positive Jacobian determinant); the frame's mirror image hardly matches.
//   * Tesseract OCR: a word written on the world reads correctly in the camera frame that sees it and
//     in every panorama, and does not read in their mirror images.
// The frames come from the simulator (sim/scene.h's photo scene: an equirect-full photo wrapped as a
// 360-degree viewer shows it) and the panoramas from the reference stitcher (stitch.h).
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omma/core/camera.h"
#include "omma/core/grid.h"
#include "omma/design/prototype.h"
#include "omma/pano/stitch.h"
#include "omma/sim/scene.h"
#include "omma/sim/simulate.h"

namespace omma {
namespace {

namespace fs = std::filesystem;

const Projection kAllProjections[] = {Projection::kVr180, Projection::kEquirect, Projection::kEquirectFull,
                                      Projection::kEquirect100};

PanoGrid grid_for(Projection p) {
  switch (p) {
    case Projection::kVr180:
      return {p, 1080, 1080};
    case Projection::kEquirect:
      return {p, 1440, 360};
    case Projection::kEquirectFull:
      return {p, 1440, 720};
    case Projection::kEquirect100:
      return {p, 1440, 400};
  }
  return {};
}

// The thesis-24 frames of a scene, ideal sensor (one ray per pixel would alias the photo: 2 x 2).
std::vector<cv::Mat> simulate_frames(const Rig& rig, const sim::Scene& scene) {
  sim::SimulateOptions so;
  so.effects = sim::CameraEffects::ideal(2);
  so.truth = false;
  so.progress = false;
  const sim::SimulateSummary r = sim::simulate(rig, scene, so);
  std::vector<cv::Mat> frames;
  for (const sim::CameraFrame& f : r.frames) frames.push_back(f.image);
  return frames;
}

cv::Mat stitch_u8(const Rig& rig, const std::vector<cv::Mat>& frames, const PanoGrid& grid) {
  pano::StitchOptions so;
  so.method = pano::Method::kLinear;
  so.grid = grid;
  so.progress = false;
  cv::Mat f = pano::stitch(rig, frames, so), u8;
  f.convertTo(u8, CV_8UC3, 255.0);
  return u8;
}

// ------------------------------------------------------------------------------------------ SIFT

struct SiftMatch {
  int inliers = 0;
  double det = 0;  // Jacobian determinant of the frame -> panorama homography at the frame centre
};

SiftMatch match_frame(const cv::Mat& frame, const std::vector<cv::KeyPoint>& pano_kp,
                      const cv::Mat& pano_desc) {
  cv::Ptr<cv::SIFT> sift = cv::SIFT::create();
  cv::Mat gray, desc;
  cv::cvtColor(frame, gray, cv::COLOR_BGR2GRAY);
  std::vector<cv::KeyPoint> kp;
  sift->detectAndCompute(gray, cv::noArray(), kp, desc);
  SiftMatch m;
  if (kp.size() < 8 || pano_kp.size() < 8) return m;
  cv::BFMatcher matcher(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> knn;
  matcher.knnMatch(desc, pano_desc, knn, 2);
  std::vector<cv::Point2f> a, b;
  for (const auto& k : knn)
    if (k.size() == 2 && k[0].distance < 0.8f * k[1].distance) {
      a.push_back(kp[k[0].queryIdx].pt);
      b.push_back(pano_kp[k[0].trainIdx].pt);
    }
  if (a.size() < 8) return m;
  cv::Mat inl;
  const cv::Mat H = cv::findHomography(a, b, cv::RANSAC, 3.0, inl);
  if (H.empty()) return m;
  m.inliers = cv::countNonZero(inl);
  // q = (H p) / w: J = (A - q h) / w with A the top-left 2x2, h = H(2, 0:2), at the frame centre.
  const double px = frame.cols / 2.0, py = frame.rows / 2.0;
  const double w = H.at<double>(2, 0) * px + H.at<double>(2, 1) * py + H.at<double>(2, 2);
  const double qx = (H.at<double>(0, 0) * px + H.at<double>(0, 1) * py + H.at<double>(0, 2)) / w;
  const double qy = (H.at<double>(1, 0) * px + H.at<double>(1, 1) * py + H.at<double>(1, 2)) / w;
  const double j00 = (H.at<double>(0, 0) - qx * H.at<double>(2, 0)) / w,
               j01 = (H.at<double>(0, 1) - qx * H.at<double>(2, 1)) / w;
  const double j10 = (H.at<double>(1, 0) - qy * H.at<double>(2, 0)) / w,
               j11 = (H.at<double>(1, 1) - qy * H.at<double>(2, 1)) / w;
  m.det = j00 * j11 - j01 * j10;
  return m;
}

// A match is a camera whose frame (or its mirror image) and the panorama share at least this many
// RANSAC inliers. Measured over the 24 cameras and four projections: lake.jpg's frames match with
// 16-260 inliers as they are and 0-12 mirrored; the Louvre courtyard is nearly symmetric, so its
// mirrored frames find 0-61 inliers, but always fewer than the same frame as it is (16-204); the
// totals differ 4-40 fold. Cameras looking at the sky (ids 0-2) match neither way.
constexpr int kMatchInliers = 15;

void check_sift_handedness(const std::string& photo) {
  const fs::path path = fs::path(OMMA_DATA_DIR) / photo;
  if (!fs::exists(path)) GTEST_SKIP() << path << " not found (../shared/data beside the checkout)";
  const Rig rig = design::thesis_prototype_rig();
  const auto scene = sim::make_photo_scene(path.string());
  const std::vector<cv::Mat> frames = simulate_frames(rig, *scene);
  for (Projection p : kAllProjections) {
    const PanoGrid grid = grid_for(p);
    const cv::Mat pano = stitch_u8(rig, frames, grid);
    cv::Mat gray, pano_desc;
    cv::cvtColor(pano, gray, cv::COLOR_BGR2GRAY);
    std::vector<cv::KeyPoint> pano_kp;
    cv::SIFT::create()->detectAndCompute(gray, gray > 0, pano_kp, pano_desc);
    // A camera "matches" when its frame or the frame's mirror image shares kMatchInliers with the
    // panorama; it must then match better as it is, through an orientation-keeping homography.
    int matched = 0, positive = 0, mirrored_better = 0, inliers = 0, inliers_flipped = 0;
    for (size_t i = 0; i < frames.size(); ++i) {
      cv::Mat flipped;
      cv::flip(frames[i], flipped, 1);
      const SiftMatch m = match_frame(frames[i], pano_kp, pano_desc);
      const SiftMatch mf = match_frame(flipped, pano_kp, pano_desc);
      inliers += m.inliers;
      inliers_flipped += mf.inliers;
      if (std::max(m.inliers, mf.inliers) >= kMatchInliers) {
        ++matched;
        positive += m.inliers >= kMatchInliers && m.det > 0;
        mirrored_better += mf.inliers >= m.inliers;
      }
      if (std::getenv("OMMA_HANDEDNESS_VERBOSE"))
        std::printf("  cam %zu: %d inliers (det %.3f), mirrored %d\n", i, m.inliers, m.det, mf.inliers);
    }
    std::printf(
        "%s %s: %d of %zu frames match, %d as they are with a positive determinant, %d better "
        "mirrored; inliers %d as they are, %d mirrored\n",
        photo.c_str(), to_string(p).c_str(), matched, frames.size(), positive, mirrored_better, inliers,
        inliers_flipped);
    EXPECT_GE(matched, 12) << to_string(p);
    EXPECT_EQ(positive, matched) << to_string(p) << ": a frame matched the panorama only mirrored";
    EXPECT_EQ(mirrored_better, 0) << to_string(p);
    EXPECT_GT(inliers, 3 * inliers_flipped) << to_string(p);
  }
}

TEST(Handedness, SiftFindsTheFramesTheSameWayRoundInEveryProjection) { check_sift_handedness("lake.jpg"); }
TEST(Handedness, SiftFindsTheFramesTheSameWayRoundOnASecondPhoto) { check_sift_handedness("louvre.jpg"); }

// ------------------------------------------------------------------------------------------- OCR

bool have_tesseract() { return std::system("tesseract --version >/dev/null 2>&1") == 0; }

// Tesseract's reading of one line of text in `img` (8-bit BGR), upper case letters only.
std::string ocr_line(const cv::Mat& img, const fs::path& dir, const std::string& name) {
  cv::Mat gray, big;
  cv::cvtColor(img, gray, cv::COLOR_BGR2GRAY);
  cv::resize(gray, big, cv::Size(), 3, 3, cv::INTER_CUBIC);
  cv::copyMakeBorder(big, big, 20, 20, 20, 20, cv::BORDER_REPLICATE);
  const fs::path png = dir / (name + ".png"), out = dir / name;
  cv::imwrite(png.string(), big);
  const std::string cmd =
      "tesseract '" + png.string() + "' '" + out.string() + "' --psm 7 -l eng >/dev/null 2>&1";
  if (std::system(cmd.c_str()) != 0) return "<tesseract failed>";
  std::ifstream in(out.string() + ".txt");
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text;
  for (char c : ss.str())
    if (std::isalpha(static_cast<unsigned char>(c)))
      text += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return text;
}

// Levenshtein distance (letters inserted, deleted or replaced).
int edit_distance(const std::string& a, const std::string& b) {
  std::vector<int> d(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) d[j] = int(j);
  for (size_t i = 1; i <= a.size(); ++i) {
    int diag = d[0];
    d[0] = int(i);
    for (size_t j = 1; j <= b.size(); ++j) {
      const int up = d[j];
      d[j] = std::min({d[j] + 1, d[j - 1] + 1, diag + (a[i - 1] != b[j - 1])});
      diag = up;
    }
  }
  return d[b.size()];
}

// The `size` x `size` patch of `img` centred on `centre` (pixels, centres at +0.5), turned (never
// mirrored) so that `up` (a direction in the image) points up; scaled by `scale`.
cv::Mat upright_patch(const cv::Mat& img, const Vec2& centre, const Vec2& up, cv::Size size, double scale) {
  const double angle = std::atan2(up.x(), -up.y());  // clockwise angle of `up` from the image's up
  const cv::Mat rot = cv::getRotationMatrix2D(cv::Point2f(float(centre.x() - 0.5), float(centre.y() - 0.5)),
                                              rad2deg(angle), scale);
  cv::Mat m = rot.clone();
  m.at<double>(0, 2) += size.width / 2.0 - (centre.x() - 0.5);
  m.at<double>(1, 2) += size.height / 2.0 - (centre.y() - 0.5);
  cv::Mat out;
  cv::warpAffine(img, out, m, size, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return out;
}

// A word written on an otherwise plain far-field world (an equirect-full image, as a 360-degree
// viewer shows it), centred on direction `at`, its letters `height_deg` tall, upright (towards +z).
cv::Mat text_world(const std::string& word, const Vec3& at, double height_deg) {
  const int W = 4096, H = 2048;
  cv::Mat world(H, W, CV_8UC3, cv::Scalar(235, 235, 235));
  const PanoGrid full{Projection::kEquirectFull, W, H};
  const Vec2 c = *full.pixel(at);
  const double theta = spherical_from_direction(at).theta;
  // The word as a plain image, then stretched by 1 / sin(theta) along the rows (the equirect's
  // horizontal scale at that polar angle), so that it has its own proportions on the sphere.
  const double px_per_deg = H / 180.0;
  int baseline = 0;
  const double font = 4.0;
  const cv::Size ts = cv::getTextSize(word, cv::FONT_HERSHEY_DUPLEX, font, 12, &baseline);
  cv::Mat label(ts.height + 2 * baseline, ts.width + 2 * baseline, CV_8UC3, cv::Scalar(235, 235, 235));
  cv::putText(label, word, cv::Point(baseline, ts.height + baseline / 2), cv::FONT_HERSHEY_DUPLEX, font,
              cv::Scalar(20, 20, 20), 12, cv::LINE_AA);
  const double s = height_deg * px_per_deg / ts.height;
  cv::resize(label, label, cv::Size(int(label.cols * s / std::sin(theta)), int(label.rows * s)), 0, 0,
             cv::INTER_AREA);
  const int x0 = int(c.x() - label.cols / 2.0), y0 = int(c.y() - label.rows / 2.0);
  label.copyTo(world(cv::Rect(x0, y0, label.cols, label.rows)));
  return world;
}

// Where an image (a camera's frame or a panorama, through `project`: direction -> optional pixel)
// shows direction `at`, and the step in pixels to `above`, a direction a little higher (towards +z):
// the step points the world's "up" there, and its length gives the image's scale.
struct Spot {
  Vec2 px, step;
};
template <typename Project>
std::optional<Spot> spot(Project project, const Vec3& at, const Vec3& above) {
  const std::optional<Vec2> p = project(at), q = project(above);
  if (!p || !q) return std::nullopt;
  return Spot{*p, *q - *p};
}

TEST(Handedness, TesseractReadsAWordInTheFramesAndEveryPanorama) {
  if (!have_tesseract()) GTEST_SKIP() << "tesseract (tesseract-ocr) not installed";
  const fs::path dir = fs::temp_directory_path() / ("omma-ocr-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const Rig rig = design::thesis_prototype_rig();
  // A view reads the word when Tesseract's reading is at most one letter off (vr180 bends the lines
  // of latitude: "GARDEN" there has read as "CARDEN"); a mirror image never comes closer than three
  // (measured: 4-7 letters off, e.g. "AAUAOD" for "CORNER").
  int read = 0, checks = 0, mirrored_read = 0;
  // Two words at two places of the 45-degree layer, one on a camera's optical axis, one beside
  // another's; each read in its nearest camera's frame and in every panorama.
  const struct {
    std::string word;
    int camera;       // the word is centred on this camera's optical axis ...
    double dphi_deg;  // ... turned by this much about +z
  } cases[] = {{"CORNER", 4, 0.0}, {"GARDEN", 8, 6.0}};
  for (const auto& c : cases) {
    const Vec3 t = rig.cameras[size_t(c.camera)].frame.t;
    const Vec3 at = Eigen::AngleAxisd(deg2rad(c.dphi_deg), Vec3::UnitZ()) * t;
    const auto scene = sim::make_photo_scene(text_world(c.word, at, 7.0), "photo:" + c.word);
    const std::vector<cv::Mat> frames = simulate_frames(rig, *scene);
    // The camera that sees the word closest to its centre.
    size_t best = 0;
    for (size_t i = 1; i < rig.cameras.size(); ++i)
      if (rig.cameras[i].frame.t.dot(at) > rig.cameras[best].frame.t.dot(at)) best = i;
    const CameraModel m = rig.cameras[best].model();
    const Vec3 above = (at + 0.01 * (Vec3::UnitZ() - at.z() * at).normalized()).normalized();
    const auto in_frame = spot([&](const Vec3& w) { return m.project(w); }, at, above);
    ASSERT_TRUE(in_frame);
    std::vector<std::pair<std::string, cv::Mat>> views;
    views.emplace_back(
        "frame cam " + std::to_string(rig.cameras[best].id),
        upright_patch(frames[best], in_frame->px, in_frame->step.normalized(), cv::Size(240, 80), 1.0));
    for (Projection p : kAllProjections) {
      const PanoGrid g = grid_for(p);
      const auto in_pano = spot([&](const Vec3& w) { return g.pixel(w); }, at, above);
      ASSERT_TRUE(in_pano) << to_string(p);
      const cv::Mat pano = stitch_u8(rig, frames, g);
      // Scaled to the frame's pixels per degree there, so that every patch holds the same view.
      views.emplace_back(to_string(p),
                         upright_patch(pano, in_pano->px, in_pano->step.normalized(), cv::Size(240, 80),
                                       in_frame->step.norm() / in_pano->step.norm()));
    }
    for (const auto& [name, patch] : views) {
      cv::Mat mirror;
      cv::flip(patch, mirror, 1);
      const std::string as_is = ocr_line(patch, dir, c.word + "_" + std::to_string(checks));
      const std::string mirrored = ocr_line(mirror, dir, c.word + "_m" + std::to_string(checks));
      std::printf("%-18s '%s': reads '%s', its mirror image '%s'\n", name.c_str(), c.word.c_str(),
                  as_is.c_str(), mirrored.c_str());
      ++checks;
      read += edit_distance(as_is, c.word) <= 1;
      mirrored_read += edit_distance(mirrored, c.word) < 3;
      EXPECT_LE(edit_distance(as_is, c.word), 1) << name << " (patches in " << dir << ")";
      EXPECT_GE(edit_distance(mirrored, c.word), 3) << name << " (patches in " << dir << ")";
    }
  }
  EXPECT_EQ(read, checks);
  EXPECT_EQ(mirrored_read, 0);
  EXPECT_EQ(checks, 10);
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace omma
