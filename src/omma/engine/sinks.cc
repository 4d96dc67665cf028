#include "omma/engine/sinks.h"

#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <httplib.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <spdlog/spdlog.h>

#include "omma/core/io.h"
#include "omma/core/metadata.h"

namespace omma::engine {
namespace fs = std::filesystem;
namespace {

std::string lower(std::string s) {
  for (auto& c : s) c = char(std::tolower((unsigned char)c));
  return s;
}

class VideoSink : public Sink {
 public:
  VideoSink(const fs::path& path, cv::Size size, double fps, std::optional<Projection> projection)
      : path_(path), size_(size), projection_(projection) {
    const std::string ext = lower(path.extension().string());
    const int fourcc = ext == ".mp4" ? cv::VideoWriter::fourcc('m', 'p', '4', 'v')
                                     : cv::VideoWriter::fourcc('M', 'J', 'P', 'G');
    const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) throw SinkError("cannot write video " + path.string() + ": folder " + dir.string() + " does not exist");
    tmp_ = dir / fmt::format(".{}.partial{}", path.stem().string(), ext);  // (fmt: GCC 12 -Wrestrict false positive on "." + string)
    if (!writer_.open(tmp_.string(), cv::CAP_FFMPEG, fourcc, fps, size, true) || !writer_.isOpened()) {
      fs::remove(tmp_, ec);
      throw SinkError("cannot write video " + path.string() + " (VideoWriter did not open; folder writable?)");
    }
  }
  ~VideoSink() override { abort(); }
  void write(const cv::Mat& pano, const FrameStore&) override { writer_.write(pano); ++frames_; }
  void finish() override {
    if (done_) return;
    done_ = true;
    writer_.release();
    std::error_code ec;
    if (frames_ == 0) {
      fs::remove(tmp_, ec);
      throw SinkError("no frames were rendered: video " + path_.string() + " not written");
    }
    if (projection_ && lower(path_.extension().string()) == ".mp4") {  // 360-degree metadata (metadata.h)
      try {
        add_spherical_video_metadata(tmp_, PanoGrid{*projection_, size_.width, size_.height});
      } catch (const IoError& e) {
        fs::remove(tmp_, ec);
        throw SinkError(e.what());
      }
    }
    fs::rename(tmp_, path_, ec);
    if (ec) {
      fs::remove(tmp_, ec);
      throw SinkError("cannot move video into place at " + path_.string());
    }
  }
  void abort() override {
    if (done_) return;
    done_ = true;
    writer_.release();
    std::error_code ec;
    fs::remove(tmp_, ec);
  }
  std::string describe() const override { return path_.string(); }

 private:
  fs::path path_, tmp_;
  cv::Size size_;
  std::optional<Projection> projection_;
  cv::VideoWriter writer_;
  long frames_ = 0;
  bool done_ = false;
};

class PngSink : public Sink {
 public:
  PngSink(const fs::path& dir, cv::Size size, std::optional<Projection> projection) : dir_(dir) {
    if (projection) grid_ = PanoGrid{*projection, size.width, size.height};
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir)) throw SinkError("cannot create PNG folder " + dir.string() + ": " + ec.message());
    // Probe that the folder is writable.
    const fs::path probe = dir / ".omma-write-probe";
    FILE* f = std::fopen(probe.c_str(), "wb");
    if (!f) throw SinkError("cannot write into PNG folder " + dir.string());
    std::fclose(f);
    fs::remove(probe, ec);
  }
  void write(const cv::Mat& pano, const FrameStore&) override {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06ld.png", n_++);
    if (grid_) write_panorama(dir_ / name, pano, *grid_);  // with the 360-degree XMP
    else write_image(dir_ / name, pano);
  }
  std::string describe() const override { return "png:" + dir_.string(); }

 private:
  fs::path dir_;
  std::optional<PanoGrid> grid_;
  long n_ = 0;
};

class PassthroughSink : public Sink {
 public:
  PassthroughSink(int cam, std::unique_ptr<Sink> inner) : cam_(cam), inner_(std::move(inner)) {}
  void write(const cv::Mat&, const FrameStore& store) override {
    const cv::Mat frame = store.camera(cam_).clone();
    inner_->write(frame, store);
  }
  void finish() override { inner_->finish(); }
  void abort() override { inner_->abort(); }
  std::string describe() const override { return "camera " + std::to_string(cam_) + " -> " + inner_->describe(); }

 private:
  int cam_;
  std::unique_ptr<Sink> inner_;
};

const char* kPage = R"(<!doctype html>
<html><head><meta charset="utf-8"><title>omma live view</title>
<style>body{background:#111;color:#ddd;font-family:sans-serif;margin:0;text-align:center}
img{max-width:100vw;max-height:92vh}#s{font-size:13px;padding:4px}</style></head>
<body><img id="v" src="/stream.mjpg" alt="omma panorama"><div id="s"></div>
<script>
setInterval(async()=>{try{const r=await fetch('/stats.json');const j=await r.json();
document.getElementById('s').textContent=`${j.frames} frames, ${(j.fps||0).toFixed(1)} fps, `+
`latency ${(j.latency_ms||0).toFixed(1)} ms, ${j.cameras_live} cameras live`;}catch(e){}},1000);
</script></body></html>
)";

class HttpSink : public Sink {
 public:
  HttpSink(int port, int quality) : port_(port), quality_(quality) {
    server_.Get("/", [](const httplib::Request&, httplib::Response& res) { res.set_content(kPage, "text/html"); });
    server_.Get("/stats.json", [this](const httplib::Request&, httplib::Response& res) {
      std::lock_guard<std::mutex> lock(mutex_);
      res.set_content(stats_.dump(), "application/json");
    });
    server_.Get("/frame.jpg", [this](const httplib::Request&, httplib::Response& res) {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait_for(lock, std::chrono::seconds(5), [&] { return seq_ > 0 || stopping_; });
      if (jpeg_.empty()) {
        res.status = 503;
        return;
      }
      res.set_content(std::string(jpeg_.begin(), jpeg_.end()), "image/jpeg");
    });
    server_.Get("/stream.mjpg", [this](const httplib::Request&, httplib::Response& res) {
      auto last = std::make_shared<long>(0);
      res.set_header("Cache-Control", "no-cache");
      res.set_chunked_content_provider(
          "multipart/x-mixed-replace; boundary=ommaframe", [this, last](size_t, httplib::DataSink& sink) {
            std::vector<uchar> jpeg;
            {
              std::unique_lock<std::mutex> lock(mutex_);
              cv_.wait_for(lock, std::chrono::milliseconds(500), [&] { return seq_ > *last || stopping_; });
              if (stopping_) {
                sink.done();
                return false;
              }
              if (seq_ == *last) return true;  // nothing new yet; keep the connection
              *last = seq_;
              jpeg = jpeg_;
            }
            const std::string head = "--ommaframe\r\nContent-Type: image/jpeg\r\nContent-Length: " +
                                     std::to_string(jpeg.size()) + "\r\n\r\n";
            if (!sink.write(head.data(), head.size())) return false;
            if (!sink.write(reinterpret_cast<const char*>(jpeg.data()), jpeg.size())) return false;
            return sink.write("\r\n", 2);
          });
    });
    server_.set_keep_alive_max_count(1);
    // SO_REUSEADDR only: httplib's default also sets SO_REUSEPORT, which would let a second server
    // bind a port that is already in use.
    server_.set_socket_options([](socket_t sock) {
      int yes = 1;
      setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, reinterpret_cast<const void*>(&yes), sizeof(yes));
    });
    if (!server_.bind_to_port("127.0.0.1", port))
      throw SinkError("cannot serve the live view on 127.0.0.1:" + std::to_string(port) +
                      " (port in use or not permitted)");
    thread_ = std::thread([this] { server_.listen_after_bind(); });
    spdlog::info("live view: http://127.0.0.1:{}/", port);
  }
  ~HttpSink() override { stop(); }
  void write(const cv::Mat& pano, const FrameStore&) override {
    std::vector<uchar> buf;
    cv::imencode(".jpg", pano, buf, {cv::IMWRITE_JPEG_QUALITY, quality_});
    {
      std::lock_guard<std::mutex> lock(mutex_);
      jpeg_.swap(buf);
      ++seq_;
    }
    cv_.notify_all();
  }
  void set_stats(const nlohmann::json& s) override {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_ = s;
  }
  void finish() override { stop(); }
  void abort() override { stop(); }
  std::string describe() const override { return "http://127.0.0.1:" + std::to_string(port_) + "/"; }

 private:
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_) return;
      stopping_ = true;
    }
    cv_.notify_all();
    server_.stop();
    if (thread_.joinable()) thread_.join();
  }
  int port_, quality_;
  httplib::Server server_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<uchar> jpeg_;
  long seq_ = 0;
  bool stopping_ = false;
  nlohmann::json stats_ = nlohmann::json::object();
};

int parse_port(const std::string& spec, const std::string& text) {
  try {
    size_t pos = 0;
    const int p = std::stoi(text, &pos);
    if (pos == text.size() && p > 0 && p < 65536) return p;
  } catch (const std::exception&) {
  }
  throw SinkError("sink '" + spec + "': expected a port number 1-65535");
}

}  // namespace

std::unique_ptr<Sink> open_sink(const std::string& spec, const Rig& rig, cv::Size pano_size, const SinkOptions& opt) {
  if (spec.rfind("http://", 0) == 0) {
    const std::string rest = spec.substr(7);
    const size_t colon = rest.rfind(':');
    if (colon == std::string::npos) throw SinkError("sink '" + spec + "': expected http://127.0.0.1:PORT");
    const std::string host = rest.substr(0, colon);
    if (host != "127.0.0.1" && host != "localhost")
      throw SinkError("sink '" + spec + "': the live view serves on 127.0.0.1 only");
    std::string port = rest.substr(colon + 1);
    if (!port.empty() && port.back() == '/') port.pop_back();
    return std::make_unique<HttpSink>(parse_port(spec, port), opt.jpeg_quality);
  }
  if (spec.rfind("http:", 0) == 0) return std::make_unique<HttpSink>(parse_port(spec, spec.substr(5)), opt.jpeg_quality);
  if (spec.rfind("cam:", 0) == 0) {
    const std::string rest = spec.substr(4);
    const size_t colon = rest.find(':');
    if (colon == std::string::npos) throw SinkError("sink '" + spec + "': expected cam:ID:SINK");
    int id = -1;
    try {
      id = std::stoi(rest.substr(0, colon));
    } catch (const std::exception&) {
      throw SinkError("sink '" + spec + "': expected cam:ID:SINK with a numeric camera id");
    }
    int index = -1;
    for (size_t c = 0; c < rig.cameras.size(); ++c)
      if (rig.cameras[c].id == id) index = int(c);
    if (index < 0) throw SinkError("sink '" + spec + "': the rig has no camera id " + std::to_string(id));
    const std::string inner = rest.substr(colon + 1);
    if (inner.rfind("cam:", 0) == 0 || inner.rfind("http", 0) == 0)
      throw SinkError("sink '" + spec + "': a passed-through camera goes to a video file or PNG folder");
    const cv::Size size(rig.cameras[index].in.width, rig.cameras[index].in.height);
    SinkOptions camera_opt = opt;
    camera_opt.spherical_metadata = false;  // a camera's frames are not panoramas
    return std::make_unique<PassthroughSink>(index, open_sink(inner, rig, size, camera_opt));
  }
  const auto metadata = opt.spherical_metadata ? std::optional(opt.projection) : std::nullopt;
  if (spec.rfind("png:", 0) == 0) return std::make_unique<PngSink>(spec.substr(4), pano_size, metadata);
  if (!spec.empty() && spec.back() == '/') return std::make_unique<PngSink>(spec, pano_size, metadata);
  const std::string ext = lower(fs::path(spec).extension().string());
  if (ext == ".mp4" || ext == ".mkv" || ext == ".avi") return std::make_unique<VideoSink>(spec, pano_size, opt.fps, metadata);
  throw SinkError("sink '" + spec + "': use FILE.mp4|.mkv|.avi, png:DIR, DIR/, cam:ID:SINK or http:PORT");
}

}  // namespace omma::engine
