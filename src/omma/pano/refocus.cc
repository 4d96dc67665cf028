#include "omma/pano/refocus.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "omma/core/progress.h"
#include "omma/pano/stitch.h"
#include "omma/pano/surface.h"

namespace omma::pano {

ApertureShape parse_aperture_shape(const std::string& name) {
  if (name == "gaussian") return ApertureShape::kGaussian;
  if (name == "box") return ApertureShape::kBox;
  throw std::invalid_argument("unknown aperture shape '" + name + "' (gaussian | box)");
}
RefocusCombine parse_refocus_combine(const std::string& name) {
  if (name == "mean") return RefocusCombine::kMean;
  if (name == "median") return RefocusCombine::kMedian;
  throw std::invalid_argument("unknown refocus combination '" + name + "' (mean | median)");
}
std::string to_string(ApertureShape s) { return s == ApertureShape::kBox ? "box" : "gaussian"; }
std::string to_string(RefocusCombine c) { return c == RefocusCombine::kMedian ? "median" : "mean"; }

bool RefocusOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = "refocus: " + m;
    return false;
  };
  if (!(focus_mm > 0)) return fail("the focus distance must be > 0 mm (or infinity)");
  if (!(aperture_mm >= 0)) return fail("the aperture must be >= 0 mm (or infinity)");
  if (!(consensus_gray >= 0 && consensus_gray <= 1)) return fail("consensus_gray must lie in [0, 1]");
  if (!(feather >= 0 && feather <= 0.5)) return fail("feather must lie in [0, 0.5]");
  if (grid.width < 1 || grid.height < 1) return fail("empty output grid");
  std::string s;
  if (!search.IsValid(&s)) return fail(s);
  return true;
}

namespace {

struct Sample {
  cv::Vec3f bgr;
  double weight;
  double gray;
};

// The consensus of kMedian: the median of the samples' gray levels, every camera one vote (an
// occluded camera near its image edge must not outvote two that see past the occluder; the mean of
// the two middle ones for an even count), then the weighted mean of the samples within `tol` of it.
cv::Vec3f consensus(std::vector<Sample>& s, double tol) {
  std::sort(s.begin(), s.end(), [](const Sample& a, const Sample& b) { return a.gray < b.gray; });
  const size_t n = s.size();
  const double median = n % 2 ? s[n / 2].gray : 0.5 * (s[n / 2 - 1].gray + s[n / 2].gray);
  cv::Vec3d sum(0, 0, 0);
  double wsum = 0;
  for (const auto& x : s)
    if (std::abs(x.gray - median) <= tol) {
      sum += cv::Vec3d(x.bgr) * x.weight;
      wsum += x.weight;
    }
  if (!(wsum > 0)) {  // no sample near the median of an even count: the two middle ones
    sum = cv::Vec3d(s[n / 2 - 1].bgr) * s[n / 2 - 1].weight + cv::Vec3d(s[n / 2].bgr) * s[n / 2].weight;
    wsum = s[n / 2 - 1].weight + s[n / 2].weight;
  }
  return cv::Vec3f(sum / wsum);
}

}  // namespace

RefocusSummary refocus(const Rig& rig, const std::vector<cv::Mat>& frames_in, const RefocusOptions& opt) {
  std::string why;
  if (!opt.IsValid(&why)) throw std::invalid_argument(why);
  check_frames(rig, frames_in);
  check_depth(opt.focus_depth, opt.grid, "focal surface depth map");
  const std::vector<cv::Mat> frames = frames_to_float(frames_in);
  const PanoGrid& grid = opt.grid;
  RefocusSummary out;
  out.image = cv::Mat(grid.height, grid.width, CV_32FC3, cv::Scalar::all(0));
  out.cameras = cv::Mat(grid.height, grid.width, CV_8UC1, cv::Scalar(0));
  const double inv2a2 = std::isinf(opt.aperture_mm) ? 0 : 1 / (2 * opt.aperture_mm * opt.aperture_mm);
  Progress progress("refocus", grid.height, opt.progress);
  tbb::parallel_for(tbb::blocked_range<int>(0, grid.height, 4), [&](const tbb::blocked_range<int>& rows) {
    std::vector<Sample> samples;
    for (int row = rows.begin(); row < rows.end(); ++row) {
      for (int col = 0; col < grid.width; ++col) {
        const double focus = opt.focus_depth.empty() ? opt.focus_mm : opt.focus_depth.at<float>(row, col);
        const auto cs = find_contributors(rig, grid.pixel_direction(col, row), focus, opt.search);
        if (cs.empty()) continue;
        // The aperture: with A = 0 (a pinhole) only the camera nearest the ray.
        double r_min = cs.front().r;
        for (const auto& c : cs) r_min = std::min(r_min, c.r);
        samples.clear();
        for (const auto& c : cs) {
          double a = 1;
          if (opt.aperture_mm == 0) {
            a = c.r == r_min ? 1 : 0;
          } else if (opt.shape == ApertureShape::kBox) {
            a = c.r <= opt.aperture_mm || c.r == r_min ? 1 : 0;  // never an empty aperture
          } else {
            // Relative to the nearest camera, so that a small aperture does not underflow to 0 everywhere
            // (the normalisation below removes the common factor exp(-r_min^2 / 2A^2)).
            a = std::exp(-(c.r * c.r - r_min * r_min) * inv2a2);
          }
          const Intrinsics& in = rig.cameras[c.camera].in;
          const double edge =
              std::min(std::min(c.px.x(), in.width - c.px.x()), std::min(c.px.y(), in.height - c.px.y()));
          const double band = opt.feather * std::min(in.width, in.height);
          const double e = band > 0 ? std::clamp(edge / band, 0.0, 1.0) : 1.0;
          // A camera's weight never reaches exactly 0 at its image edge when it is the only one.
          const double w = a * std::max(e, 1e-6);
          if (!(w > 1e-12)) continue;
          const cv::Vec3f bgr = sample_bilinear(frames[c.camera], c.px);
          samples.push_back({bgr, w, luma(bgr)});
        }
        if (samples.empty()) continue;
        cv::Vec3f v;
        if (opt.combine == RefocusCombine::kMedian && samples.size() > 2) {
          v = consensus(samples, opt.consensus_gray);
        } else {
          cv::Vec3d sum(0, 0, 0);
          double wsum = 0;
          for (const auto& s : samples) {
            sum += cv::Vec3d(s.bgr) * s.weight;
            wsum += s.weight;
          }
          v = cv::Vec3f(sum / wsum);
        }
        out.image.at<cv::Vec3f>(row, col) = v;
        out.cameras.at<uint8_t>(row, col) = static_cast<uint8_t>(std::min<size_t>(255, samples.size()));
      }
      progress.step();
    }
  });
  progress.finish();
  const cv::Mat seen = out.cameras > 0;
  out.mean_cameras = cv::countNonZero(seen) ? cv::mean(out.cameras, seen)[0] : 0;
  return out;
}

double edge_width_10_90(const cv::Mat& image, const cv::Rect& roi) {
  if (roi.width < 8 || roi.height < 8 || (roi & cv::Rect(0, 0, image.cols, image.rows)) != roi)
    throw std::invalid_argument("edge_width_10_90: the region must lie inside the image and be at least 8x8");
  cv::Mat g;
  {
    cv::Mat f;
    image(roi).convertTo(f, CV_32F,
                         image.depth() == CV_8U    ? 1.0 / 255
                         : image.depth() == CV_16U ? 1.0 / 65535
                                                   : 1.0);
    if (f.channels() == 3)
      cv::cvtColor(f, g, cv::COLOR_BGR2GRAY);
    else
      g = f;
  }
  // Orientation: an edge closer to horizontal has larger vertical gradients; transpose it to vertical.
  cv::Mat gx, gy;
  cv::Sobel(g, gx, CV_32F, 1, 0);
  cv::Sobel(g, gy, CV_32F, 0, 1);
  if (cv::sum(cv::abs(gy))[0] > cv::sum(cv::abs(gx))[0]) g = g.t();
  double lo, hi;
  cv::minMaxLoc(g, &lo, &hi);
  if (hi - lo < 0.05) return std::numeric_limits<double>::quiet_NaN();
  // Edge position per row: centroid of the absolute central difference.
  std::vector<double> ys, xs;
  for (int r = 0; r < g.rows; ++r) {
    const float* p = g.ptr<float>(r);
    double m = 0, mx = 0;
    for (int c = 1; c + 1 < g.cols; ++c) {
      const double d = std::abs(p[c + 1] - p[c - 1]);
      m += d;
      mx += d * (c + 0.5);
    }
    if (m > 1e-6) {
      ys.push_back(r + 0.5);
      xs.push_back(mx / m);
    }
  }
  if (ys.size() < 4) return std::numeric_limits<double>::quiet_NaN();
  // Least-squares line x = a + b y.
  double sy = 0, sx = 0, syy = 0, sxy = 0;
  const double n = double(ys.size());
  for (size_t i = 0; i < ys.size(); ++i) {
    sy += ys[i];
    sx += xs[i];
    syy += ys[i] * ys[i];
    sxy += ys[i] * xs[i];
  }
  const double den = n * syy - sy * sy;
  const double b = den > 1e-9 ? (n * sxy - sy * sx) / den : 0, a = (sx - b * sy) / n;
  const double cosang = 1 / std::sqrt(1 + b * b);
  // Binned ESF at 1/4 pixel over the signed distance from the line.
  const double bin = 0.25;
  const int half = int(std::ceil(g.cols / bin));
  std::vector<double> sum(2 * half + 1, 0), cnt(2 * half + 1, 0);
  for (int r = 0; r < g.rows; ++r) {
    const float* p = g.ptr<float>(r);
    const double x_edge = a + b * (r + 0.5);
    for (int c = 0; c < g.cols; ++c) {
      const double d = (c + 0.5 - x_edge) * cosang;
      const int k = int(std::lround(d / bin)) + half;
      if (k < 0 || k > 2 * half) continue;
      sum[k] += p[c];
      cnt[k] += 1;
    }
  }
  std::vector<double> esf, pos;
  for (int k = 0; k <= 2 * half; ++k)
    if (cnt[k] > 0) {
      esf.push_back(sum[k] / cnt[k]);
      pos.push_back((k - half) * bin);
    }
  if (esf.size() < 8) return std::numeric_limits<double>::quiet_NaN();
  const size_t q = std::max<size_t>(1, esf.size() / 4);
  double left = 0, right = 0;
  for (size_t i = 0; i < q; ++i) {
    left += esf[i];
    right += esf[esf.size() - 1 - i];
  }
  left /= q;
  right /= q;
  if (std::abs(right - left) < 0.05) return std::numeric_limits<double>::quiet_NaN();
  // Normalised rising ESF; the first crossings of 10 % from the left and of 90 % from the right.
  auto level = [&](size_t i) { return (esf[i] - left) / (right - left); };
  // Linear interpolation between samples i - 1 and i where the level crosses t (the sample itself
  // where the ESF does not rise there).
  auto at = [&](size_t i, double t) {
    const double l0 = level(i - 1), l1 = level(i);
    if (!(l1 > l0)) return pos[i];
    return pos[i - 1] + (t - l0) / (l1 - l0) * (pos[i] - pos[i - 1]);
  };
  auto cross = [&](double t, bool from_left) {
    if (from_left) {
      for (size_t i = 1; i < esf.size(); ++i)
        if (level(i) >= t) return at(i, t);
      return pos.back();
    }
    for (size_t i = esf.size() - 1; i > 0; --i)
      if (level(i - 1) <= t) return at(i, t);
    return pos.front();
  };
  const double width = std::max(0.0, cross(0.9, false) - cross(0.1, true));
  // A width beyond the region's own extent measures nothing (the edge spread past the region).
  if (width > 0.75 * g.cols) return std::numeric_limits<double>::quiet_NaN();
  return width;
}

std::vector<DefocusBin> sharpness_by_defocus(const cv::Mat& image, const cv::Mat& truth,
                                             const cv::Mat& depth_mm, double focus_mm,
                                             const std::vector<double>& edges, const cv::Mat& mask) {
  if (image.size() != truth.size() || depth_mm.size() != truth.size() || depth_mm.type() != CV_32FC1)
    throw std::invalid_argument("sharpness_by_defocus: image, truth and depth (CV_32FC1) must have one size");
  if (edges.empty() || !std::is_sorted(edges.begin(), edges.end()))
    throw std::invalid_argument("sharpness_by_defocus: the bin edges must be ascending");
  if (!mask.empty() && (mask.size() != truth.size() || mask.type() != CV_8UC1))
    throw std::invalid_argument("sharpness_by_defocus: the mask must be CV_8UC1 of the truth's size");
  auto gray = [](const cv::Mat& m) {
    cv::Mat f, g;
    m.convertTo(f, CV_32F, m.depth() == CV_8U ? 1.0 / 255 : m.depth() == CV_16U ? 1.0 / 65535 : 1.0);
    if (f.channels() == 3)
      cv::cvtColor(f, g, cv::COLOR_BGR2GRAY);
    else
      g = f;
    return g;
  };
  auto energy = [](const cv::Mat& g) {
    cv::Mat gx, gy;
    cv::Sobel(g, gx, CV_32F, 1, 0, 1);
    cv::Sobel(g, gy, CV_32F, 0, 1, 1);
    return cv::Mat(gx.mul(gx) + gy.mul(gy));
  };
  const cv::Mat ei = energy(gray(image)), et = energy(gray(truth));
  const double inv_f = std::isinf(focus_mm) ? 0 : 1 / focus_mm;
  std::vector<DefocusBin> bins(edges.size());
  std::vector<double> si(edges.size(), 0), st(edges.size(), 0);
  for (size_t b = 0; b < edges.size(); ++b) {
    bins[b].from = edges[b];
    bins[b].to = b + 1 < edges.size() ? edges[b + 1] : std::numeric_limits<double>::infinity();
  }
  for (int r = 1; r + 1 < truth.rows; ++r)
    for (int c = 1; c + 1 < truth.cols; ++c) {
      const float z = depth_mm.at<float>(r, c);
      if (!(z > 0) || (!mask.empty() && mask.at<uint8_t>(r, c) == 0)) continue;
      const double t = et.at<float>(r, c);
      if (t < 1e-4) continue;  // no texture in the truth
      const double d = std::abs((std::isinf(z) ? 0 : 1 / z) - inv_f);
      const auto it = std::upper_bound(edges.begin(), edges.end(), d);
      if (it == edges.begin()) continue;
      const size_t b = size_t(it - edges.begin()) - 1;
      si[b] += ei.at<float>(r, c);
      st[b] += t;
      ++bins[b].pixels;
    }
  for (size_t b = 0; b < bins.size(); ++b)
    bins[b].energy_ratio = st[b] > 0 ? si[b] / st[b] : std::numeric_limits<double>::quiet_NaN();
  return bins;
}

}  // namespace omma::pano
