#include "omma/live/sources.h"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/core/parse.h"
#include "omma/core/valid.h"
#include "omma/isp/isp.h"
#include "omma/isp/link.h"
#include "omma/isp/photometric.h"
#include "omma/live/gst.h"
#include "omma/live/sim_loop.h"
#include "omma/sim/panorama_views.h"

namespace omma::live {
namespace fs = std::filesystem;
namespace {

bool has_ext(const fs::path& p, std::initializer_list<const char*> exts) {
  const std::string e = lower_extension(p);
  for (const char* x : exts)
    if (e == x) return true;
  return false;
}

class ImageSequence : public CameraSource {
 public:
  ImageSequence(const fs::path& dir, double fps, bool loop) : dir_(dir), fps_(fps), loop_(loop) {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec))
      if (e.is_regular_file() && has_ext(e.path(), {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff"}))
        files_.push_back(e.path());
    if (ec) throw SourceError("cannot read image-sequence folder " + dir.string() + ": " + ec.message());
    if (files_.empty()) throw SourceError("image-sequence folder " + dir.string() + " holds no images");
    std::sort(files_.begin(), files_.end());
  }
  bool read(cv::Mat& frame) override {
    if (next_ >= files_.size()) {
      if (!loop_) return false;
      next_ = 0;
    }
    frame = read_image(files_[next_++]);  // throws IoError naming the file
    return true;
  }
  double fps() const override { return fps_; }
  std::string describe() const override { return dir_.string(); }

 private:
  fs::path dir_;
  std::vector<fs::path> files_;
  size_t next_ = 0;
  double fps_;
  bool loop_;
};

class Video : public CameraSource {
 public:
  Video(const std::string& spec, int device, const SourceOptions& opt) : spec_(spec), loop_(opt.loop) {
    const bool ok = device >= 0 ? cap_.open(device, cv::CAP_V4L2) : cap_.open(spec, cv::CAP_FFMPEG);
    if (!ok || !cap_.isOpened())
      throw SourceError("cannot open " + std::string(device >= 0 ? "V4L2 device " : "video file ") + spec);
    const double f = cap_.get(cv::CAP_PROP_FPS);
    fps_ = (opt.force_fps || !(f > 0 && f < 1000)) ? opt.fps : f;
    device_ = device >= 0;
  }
  bool read(cv::Mat& frame) override {
    if (cap_.read(frame) && !frame.empty()) return true;
    if (loop_ && !device_ && cap_.set(cv::CAP_PROP_POS_FRAMES, 0) && cap_.read(frame) && !frame.empty())
      return true;
    if (device_) throw SourceError("V4L2 device " + spec_ + " stopped delivering frames");
    return false;
  }
  // Devices pace themselves; files are paced to their frame rate.
  double fps() const override { return device_ ? 0 : fps_; }
  std::string describe() const override { return spec_; }

 private:
  std::string spec_;
  cv::VideoCapture cap_;
  double fps_ = 30;
  bool loop_, device_ = false;
};

class Still : public CameraSource {
 public:
  Still(cv::Mat f, double fps, int limit, bool fail, std::string what)
      : frame_(std::move(f)), fps_(fps), limit_(limit), fail_(fail), what_(std::move(what)) {}
  bool read(cv::Mat& frame) override {
    if (limit_ > 0 && n_ >= limit_) {
      if (fail_)
        throw SourceError(what_ + ": simulated camera failure after " + std::to_string(n_) + " frames");
      return false;
    }
    ++n_;
    frame = frame_;
    return true;
  }
  double fps() const override { return fps_; }
  std::string describe() const override { return what_; }

 private:
  cv::Mat frame_;
  double fps_;
  int limit_, n_ = 0;
  bool fail_;
  std::string what_;
};

// Views of a turning 360x180 photograph: camera c's remap table is computed once; turning the
// world by yaw about the dome axis shifts the photograph's columns (cv::BORDER_WRAP).
struct PanoScene {
  cv::Mat pano, wide;
  std::vector<cv::Mat> map_x, map_y;  // per camera, CV_32F
  double deg_per_s = 10;
  std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
};

class PanoView : public CameraSource {
 public:
  PanoView(std::shared_ptr<PanoScene> s, int cam, double fps, std::string spec)
      : scene_(std::move(s)), cam_(cam), fps_(fps), spec_(std::move(spec)) {}
  bool read(cv::Mat& frame) override {
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - scene_->t0).count();
    // `wide` is the photograph twice side by side: a shift in [0, W) needs no wrapping.
    const double w = scene_->pano.cols;
    double shift = std::fmod(scene_->deg_per_s * t / 360.0 * w, w);
    if (shift < 0) shift += w;
    cv::add(scene_->map_x[cam_], cv::Scalar(shift), map_x_);
    cv::remap(scene_->wide, frame, map_x_, scene_->map_y[cam_], cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    return true;
  }
  double fps() const override { return fps_; }
  std::string describe() const override { return spec_ + " camera " + std::to_string(cam_); }

 private:
  std::shared_ptr<PanoScene> scene_;
  cv::Mat map_x_;
  int cam_;
  double fps_;
  std::string spec_;
};

// A raw sensor-link file (isp/link.h, chips packed 8 per byte) of one camera: the link decoder
// runs in a background thread into a small queue; each frame's damaged rows are concealed and the
// ISP (isp/isp.h) develops it to 8-bit BGR. A camera with a photometric model is developed with the
// model as the ISP's flat gain and no automatic white balance (isp/photometric.h).
class LinkFile : public CameraSource {
 public:
  LinkFile(const fs::path& path, const RigCamera& cam, double fps, bool loop)
      : path_(path), fps_(fps), loop_(loop) {
    if (cam.photometric) {
      isp_.flat_gain = isp::flat_gain_from_model(*cam.photometric, cam.in.width, cam.in.height);
      isp_.awb = isp::Awb::kNone;
    }
    config_.width = cam.in.width;
    config_.height = cam.in.height;
    try {
      bytes_ = read_file(path, kMaxDataFileBytes, "sensor-link file");
    } catch (const IoError& e) {
      throw SourceError(e.what());
    }
    if (bytes_.empty()) throw SourceError("sensor-link file " + path.string() + " is empty");
    try {
      thread_ = std::thread([this] { decode(); });
    } catch (const std::system_error& e) {
      throw SourceError("cannot start the decoder thread of sensor-link file " + path.string() + ": " +
                        e.what());
    }
  }
  ~LinkFile() override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    if (thread_.joinable()) thread_.join();
  }
  bool read(cv::Mat& frame) override {
    isp::LinkFrame lf;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [&] { return !queue_.empty() || done_; });
      if (queue_.empty()) {
        if (!error_.empty()) throw SourceError(error_);
        if (decoded_ == 0)
          throw SourceError("sensor-link file " + path_.string() + " holds no decodable frame");
        return false;
      }
      lf = std::move(queue_.front());
      queue_.erase(queue_.begin());
    }
    cv_.notify_all();
    isp::conceal_damaged_rows(lf);
    frame = isp::develop(isp::to_mat(lf), isp_);
    return true;
  }
  double fps() const override { return fps_; }
  std::string describe() const override { return "link:" + path_.string(); }
  bool photometric_applied() const override { return !isp_.flat_gain.empty(); }

 private:
  struct Stop {};
  void decode() {
    try {
      do {
        isp::decode_link(bytes_, config_, [this](const isp::LinkFrame& f) {
          std::unique_lock<std::mutex> lock(mutex_);
          cv_.wait(lock, [&] { return queue_.size() < 3 || stop_; });
          if (stop_) throw Stop{};
          queue_.push_back(f);
          ++decoded_;
          cv_.notify_all();
        });
      } while (loop_ && decoded_ > 0 && !stop_);
    } catch (const Stop&) {
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = "sensor-link file " + path_.string() + ": " + e.what();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    done_ = true;
    cv_.notify_all();
  }
  fs::path path_;
  isp::IspOptions isp_;
  isp::LinkConfig config_;
  std::vector<uint8_t> bytes_;
  double fps_;
  bool loop_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<isp::LinkFrame> queue_;
  long decoded_ = 0;
  bool stop_ = false, done_ = false;
  std::string error_;
};

std::unique_ptr<CameraSource> open_one(const std::string& spec, const RigCamera& cam,
                                       const SourceOptions& opt) {
  if (spec.rfind("gst:", 0) == 0) return open_gst_source(spec.substr(4), cam, opt);  // gst.h
  if (spec.rfind("link:", 0) == 0 || has_ext(fs::path(spec), {".bin"})) {
    const fs::path p = spec.rfind("link:", 0) == 0 ? spec.substr(5) : spec;
    return std::make_unique<LinkFile>(p, cam, opt.fps, opt.loop);
  }
  if (spec.rfind("v4l2:", 0) == 0 || spec.rfind("/dev/video", 0) == 0) {
    const std::string num = spec.substr(spec.rfind("v4l2:", 0) == 0 ? 5 : 10);
    int dev = -1;
    try {
      size_t pos = 0;
      dev = std::stoi(num, &pos);
      if (pos != num.size() || dev < 0) throw std::invalid_argument(num);
    } catch (const std::exception&) {
      throw SourceError("source '" + spec + "': expected v4l2:N or /dev/videoN");
    }
    if (spec[0] == '/' && !fs::exists(spec))
      throw SourceError("cannot open V4L2 device " + spec + ": no such device");
    return std::make_unique<Video>(spec, dev, opt);
  }
  const fs::path p(spec);
  std::error_code ec;
  if (fs::is_directory(p, ec)) return std::make_unique<ImageSequence>(p, opt.fps, opt.loop);
  if (!fs::exists(p, ec)) throw SourceError("source '" + spec + "': no such file or folder");
  if (has_ext(p, {".mp4", ".mkv", ".avi", ".mov", ".webm", ".m4v", ".mjpeg", ".mjpg"}))
    return std::make_unique<Video>(spec, -1, opt);
  throw SourceError("source '" + spec +
                    "': not a folder, a video file (.mp4 .mkv .avi .mov .webm) or a device");
}

// "NAME@RATE" (sim:colon@2.5, pano:x.jpg@30): strips "@RATE" from `spec` and returns the rate,
// nullopt without '@'; a rate that is not a number is a SourceError naming `source` and `form`.
std::optional<double> split_rate(std::string& spec, const std::string& source, const char* form) {
  const size_t at = spec.rfind('@');
  if (at == std::string::npos) return std::nullopt;
  const std::optional<double> parsed = parse_double(spec.substr(at + 1));  // core/parse.h
  if (!parsed) throw SourceError("source '" + source + "': expected " + form);
  const double rate = *parsed;
  if (!(std::abs(rate) <= kMaxSimSpeed))
    throw SourceError(fmt::format("source '{}': the rate must be a number in [-{}, {}]", source, kMaxSimSpeed,
                                  kMaxSimSpeed));
  spec.resize(at);
  return rate;
}

}  // namespace

std::unique_ptr<CameraSource> still_source(cv::Mat frame, double fps, int limit, bool fail) {
  return std::make_unique<Still>(std::move(frame), fps, limit, fail, "still");
}

bool SourceOptions::IsValid(std::string* why) const {
  if (!valid_rate(fps, true))
    return invalid(why, fmt::format("fps must be 0 (as fast as possible) or {}..{}", kMinRate, kMaxRate));
  if (!(stall_s > 0 && stall_s <= 1e6)) return invalid(why, "stall_s must be in (0, 1e6] seconds");
  return sim.IsValid(why);
}

std::vector<std::unique_ptr<CameraSource>> open_sources(const Rig& rig,
                                                        const std::vector<std::string>& specs_in,
                                                        const SourceOptions& opt) {
  const size_t n = rig.cameras.size();
  std::vector<std::unique_ptr<CameraSource>> out;
  if (specs_in.empty()) throw SourceError("no --source given");
  if (std::string why; !opt.IsValid(&why)) throw SourceError("source options: " + why);
  std::vector<std::string> specs = specs_in;
  if (specs.size() == 1 && specs[0].find("{id}") != std::string::npos) {
    const std::string pattern = specs[0];
    specs.clear();
    for (const auto& cam : rig.cameras) {
      char id[16];
      std::snprintf(id, sizeof id, "%02d", cam.id);
      std::string s = pattern;
      for (size_t pos; (pos = s.find("{id}")) != std::string::npos;) s.replace(pos, 4, id);
      specs.push_back(s);
    }
  }
  if (specs.size() == 1 && specs[0].rfind("frames:", 0) == 0) {
    const fs::path dir = specs[0].substr(7);
    std::vector<cv::Mat> frames;
    try {
      frames = load_frames(dir, rig);
    } catch (const std::exception& e) {
      throw SourceError("source '" + specs[0] + "': " + e.what());
    }
    for (size_t c = 0; c < n; ++c)
      out.push_back(std::make_unique<Still>(frames[c], opt.fps, 0, false,
                                            specs[0] + " " + frame_filename(rig.cameras[c].id)));
    return out;
  }
  if (specs.size() == 1 && specs[0].rfind("sim:", 0) == 0) {
    std::string scene = specs[0].substr(4);
    const auto speed = split_rate(scene, specs[0], "sim:SCENE@SPEED");
    return std::make_shared<SimLoop>(rig, scene, speed, opt.sim)->sources();
  }
  if (specs.size() == 1 && specs[0].rfind("pano:", 0) == 0) {
    std::string path = specs[0].substr(5);
    auto scene = std::make_shared<PanoScene>();
    if (const auto rate = split_rate(path, specs[0], "pano:IMAGE@DEG_PER_S")) scene->deg_per_s = *rate;
    try {
      scene->pano = read_image(path, cv::IMREAD_COLOR);
    } catch (const std::exception& e) {
      throw SourceError("source '" + specs[0] + "': " + e.what());
    }
    // About the cameras' resolution (with margin), so that the views are not aliased.
    double px_per_rad = 0;
    for (const auto& c : rig.cameras) px_per_rad = std::max(px_per_rad, c.in.fu);
    const int w = std::min(scene->pano.cols, std::max(64, int(2 * kPi * px_per_rad * 1.5)));
    if (w < scene->pano.cols) cv::resize(scene->pano, scene->pano, cv::Size(w, w / 2), 0, 0, cv::INTER_AREA);
    cv::hconcat(scene->pano, scene->pano, scene->wide);
    for (const cv::Mat& m : sim::panorama_to_camera_maps(rig, scene->pano.size())) {
      std::vector<cv::Mat> xy;
      cv::split(m, xy);
      scene->map_x.push_back(xy[0]);
      scene->map_y.push_back(xy[1]);
    }
    for (size_t c = 0; c < n; ++c)
      out.push_back(std::make_unique<PanoView>(scene, int(c), opt.fps, specs[0]));
    return out;
  }
  if (specs.size() != n)
    throw SourceError("got " + std::to_string(specs.size()) + " sources for a rig of " + std::to_string(n) +
                      " cameras: give one per camera (rig order), a {id} pattern, frames:DIR or pano:IMAGE");
  for (size_t c = 0; c < n; ++c) out.push_back(open_one(specs[c], rig.cameras[c], opt));
  return out;
}

}  // namespace omma::live
