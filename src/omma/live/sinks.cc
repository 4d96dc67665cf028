#include "omma/live/sinks.h"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <string_view>
#include <thread>

#include <fmt/format.h>
#include <httplib.h>
#include <ifaddrs.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <spdlog/spdlog.h>

#include "omma/core/io.h"
#include "omma/core/valid.h"
#include "omma/io/metadata.h"
#include "omma/io/video_writer.h"
#include "omma/live/engine.h"
#include "omma/live/gst.h"
#include "omma/live/sources.h"
#include "omma/live/web_assets.h"

namespace omma::live {
namespace fs = std::filesystem;
namespace {

// A video file through io::VideoWriter (H.264 / VP9, atomic: the temporary file .NAME.partial.EXT
// is renamed into place by finish(), removed by abort()), with the 360-degree metadata of its
// projection.
class VideoSink : public Sink {
 public:
  VideoSink(const fs::path& path, cv::Size size, const io::VideoOptions& options,
            std::optional<Projection> projection)
      : path_(path) {
    try {
      writer_ = std::make_unique<io::VideoWriter>(path, size, options, projection);
    } catch (const std::exception& e) {
      throw SinkError(e.what());
    }
  }
  ~VideoSink() override { abort(); }
  void write(const cv::Mat& pano, const render::FrameStore&) override {
    try {
      writer_->write(pano);
    } catch (const std::exception& e) {
      throw SinkError(std::string(e.what()) + "; nothing was left under its name");
    }
  }
  void finish() override {
    if (done_) return;
    done_ = true;
    try {
      writer_->close();
    } catch (const std::exception& e) {
      throw SinkError(std::string(e.what()) + "; nothing was left under its name");
    }
  }
  void abort() override {
    if (done_) return;
    done_ = true;
    writer_->abort();
  }
  std::string describe() const override { return path_.string(); }

 private:
  fs::path path_;
  std::unique_ptr<io::VideoWriter> writer_;
  bool done_ = false;
};

// Raw frames on stdout (`--sink -`): each panorama as width x height x 3 bytes, row by row, BGR
// (FFmpeg's rawvideo bgr24), nothing else; the size and rate are stated on stderr at the start. A
// reader that goes away (EPIPE: ffmpeg -frames N, head -c) stops the run as Ctrl-C does, and the
// other sinks are finished.
class StdoutSink : public Sink {
 public:
  StdoutSink(cv::Size size, double fps) : size_(size) {
    std::signal(SIGPIPE, SIG_IGN);  // a closed pipe is a write error, not the end of the process
    std::fprintf(
        stderr,
        "omma: raw video on stdout: %dx%d bgr24 at %g frames/s (ffmpeg -f rawvideo -pix_fmt bgr24 -s "
        "%dx%d -r %g -i - OUT)\n",
        size.width, size.height, fps, size.width, size.height, fps);
  }
  void write(const cv::Mat& pano, const render::FrameStore&) override {
    if (closed_) return;
    if (pano.size() != size_ || pano.type() != CV_8UC3)
      throw SinkError("stdout: unexpected frame size or type");
    const cv::Mat c = pano.isContinuous() ? pano : pano.clone();
    const char* p = reinterpret_cast<const char*>(c.data);
    for (size_t left = c.total() * c.elemSize(); left > 0;) {
      const ssize_t n = ::write(STDOUT_FILENO, p, left);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && errno == EPIPE) {
        spdlog::info("the reader of stdout closed it: stopping");
        closed_ = true;
        request_stop();
        return;
      }
      if (n <= 0) throw SinkError(std::string("cannot write raw video to stdout: ") + std::strerror(errno));
      p += n;
      left -= size_t(n);
    }
  }
  std::string describe() const override { return "-"; }

 private:
  cv::Size size_;
  bool closed_ = false;
};

class PngSink : public Sink {
 public:
  PngSink(const fs::path& dir, cv::Size size, std::optional<Projection> projection) : dir_(dir) {
    if (projection) grid_ = PanoGrid{*projection, size.width, size.height};
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir))
      throw SinkError("cannot create PNG folder " + dir.string() + ": " + ec.message());
    // Temporary files of frames (core/io.h: .frame_NNNNNN.tmpRANDOM.png) left by a killed run.
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      const std::string name = e.path().filename().string();
      if (name.rfind(".frame_", 0) == 0 && name.find(".tmp") != std::string::npos &&
          e.path().extension() == ".png")
        remove_leftover(e.path(), dir / name.substr(1, name.find(".tmp") - 1).append(".png"));
    }
    // Probe that the folder is writable.
    const fs::path probe = dir / ".omma-write-probe";
    FILE* f = std::fopen(probe.c_str(), "wb");
    if (!f) throw SinkError("cannot write into PNG folder " + dir.string());
    std::fclose(f);
    fs::remove(probe, ec);
  }
  void write(const cv::Mat& pano, const render::FrameStore&) override {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06ld.png", n_++);
    if (grid_)
      io::write_panorama(dir_ / name, pano, *grid_);  // with the 360-degree XMP
    else
      write_image(dir_ / name, pano);
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
  void write(const cv::Mat&, const render::FrameStore& store) override {
    const cv::Mat frame = store.camera(cam_).clone();
    inner_->write(frame, store);
  }
  void finish() override { inner_->finish(); }
  void abort() override { inner_->abort(); }
  std::string describe() const override {
    return "camera " + std::to_string(cam_) + " -> " + inner_->describe();
  }

 private:
  int cam_;
  std::unique_ptr<Sink> inner_;
};

// The live view's HTTP server: cpp-httplib parses the requests and writes the answers; the
// connections are this code's, so that no client can starve another (any web page the user visits
// can reach 127.0.0.1, and with --bind anyone on the network the address it serves). Limits:
//   - every connection runs on a thread of its own (ConnectionThreads), up to a cap of
//     max_streams + kOtherConnections open at once; past the cap a new connection is answered 503
//     (Retry-After: 1) by the accepting thread at once and closed;
//   - a connection must deliver its request (request line and headers, at most kMaxRequestBytes,
//     no body) within kRequestDeadline of being accepted, however slowly it trickles, or it is
//     closed: idle and slowloris connections hold their thread for at most that long. One request
//     per connection (no keep-alive), so a connection never idles after its answer either;
//   - only GET and HEAD, without a body: other methods are answered 405, a body 413, from the
//     headers, before a byte of the body is read;
//   - Range is ignored (RFC 9110 allows it): every answer is the whole resource, once, so a
//     multi-range request cannot multiply a response (nor ask for bytes past its end);
//   - a write that cannot progress for kWriteTimeout ends its connection (a viewer that stopped
//     reading); at most max_streams streams (the next gets 503 + Retry-After).
// Guarantee: while fewer connections than the cap are open, a request that arrives is answered at
// once (the page, /stats.json, a frame), whatever the other connections do: idle, trickling,
// streaming or downloading, none of them shares its thread. The streams take at most max_streams
// places, so kOtherConnections (256) stay for everything else. Limits: past the cap new
// connections, the page's too, get 503 until some end; as every connection that is not a stream
// ends within kRequestDeadline plus its answer, holding the server at its cap takes a client that
// reopens hundreds of connections every 2 s (a browser gives a page a few connections per host); a
// refused client may see a reset instead of the 503. A connection's thread costs about 8 MB of
// address space (its stack, reserved) and some tens of kB of memory; a request at most
// kMaxRequestBytes (and 8 kB a header line, httplib's limit). stop() cuts every connection's wait
// within kPollSlice and joins their threads: no client can hold it.
constexpr size_t kOtherConnections = 256;
constexpr size_t kMaxRequestBytes = 16 * 1024;
constexpr auto kRequestDeadline = std::chrono::seconds(2);
constexpr auto kWriteTimeout = std::chrono::seconds(5);
constexpr auto kPollSlice = std::chrono::milliseconds(100);  // how often a waiting thread sees stop()
using Clock = std::chrono::steady_clock;

// Set while the accepting thread itself runs a connection it has no thread for (past the cap).
thread_local bool t_over_capacity = false;

// The server's task queue: each connection on a thread of its own, up to `cap` at once. A
// connection past the cap runs on the accepting thread, which answers it 503 at once
// (LiveServer::process_and_close_socket). httplib calls enqueue() and shutdown() from its accepting
// thread only; shutdown() joins every connection's thread.
class ConnectionThreads : public httplib::TaskQueue {
 public:
  explicit ConnectionThreads(size_t cap) : cap_(cap) {}
  ~ConnectionThreads() override { shutdown(); }
  void enqueue(std::function<void()> fn) override {
    auto task = std::make_shared<std::function<void()>>(std::move(fn));
    {
      std::lock_guard<std::mutex> lock(mutex_);
      reap();
      if (threads_.size() < cap_) {
        const auto it = threads_.emplace(threads_.end());
        try {
          *it = std::thread([this, it, task] {
            (*task)();
            std::lock_guard<std::mutex> done(mutex_);
            finished_.push_back(it);
          });
          return;
        } catch (const std::system_error&) {  // no thread to be had: refused like past the cap
          threads_.erase(it);
        }
      }
    }
    t_over_capacity = true;
    (*task)();
    t_over_capacity = false;
  }
  void shutdown() override {
    std::list<std::thread> all;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      all.swap(threads_);
    }
    for (auto& t : all)
      if (t.joinable()) t.join();
    std::lock_guard<std::mutex> lock(mutex_);
    finished_.clear();
  }

 private:
  // Joins the threads whose connection has ended (under mutex_; they are past their last use of it).
  void reap() {
    for (const auto& it : finished_) {
      it->join();
      threads_.erase(it);
    }
    finished_.clear();
  }
  const size_t cap_;
  std::mutex mutex_;
  std::list<std::thread> threads_;
  std::vector<std::list<std::thread>::iterator> finished_;
};

class LiveServer : public httplib::Server {
 public:
  // httplib listens with a backlog of 5; a burst of connections waits in a longer queue instead of
  // being dropped (and retried by the client a second later).
  void widen_backlog() { ::listen(svr_sock_, SOMAXCONN); }
  bool stopping() const { return svr_sock_ == INVALID_SOCKET; }

 private:
  bool process_and_close_socket(socket_t sock) override;
};

// One connection as httplib's Stream: reads until the request's deadline and at most
// kMaxRequestBytes, writes that give up after kWriteTimeout without progress, and every wait cut
// short by stop().
class ConnectionStream : public httplib::Stream {
 public:
  ConnectionStream(socket_t sock, const LiveServer& server)
      : sock_(sock), server_(server), read_deadline_(Clock::now() + kRequestDeadline) {}
  bool is_readable() const override { return off_ < len_ || wait(POLLIN, read_deadline_); }
  // Writable within kWriteTimeout, and the viewer has not gone (it never half-closes).
  bool is_writable() const override {
    pollfd p{sock_, POLLRDHUP, 0};
    if (::poll(&p, 1, 0) == 1 && (p.revents & (POLLRDHUP | POLLHUP | POLLERR))) return false;
    return wait(POLLOUT, Clock::now() + kWriteTimeout);
  }
  ssize_t read(char* ptr, size_t size) override {
    if (off_ == len_) {
      if (received_ >= kMaxRequestBytes || !wait(POLLIN, read_deadline_)) return -1;
      const ssize_t n = ::recv(sock_, buf_, std::min(sizeof buf_, kMaxRequestBytes - received_), 0);
      if (n <= 0) return n < 0 ? -1 : 0;
      received_ += size_t(n);
      off_ = 0;
      len_ = size_t(n);
    }
    const size_t n = std::min(size, len_ - off_);
    std::memcpy(ptr, buf_ + off_, n);
    off_ += n;
    return ssize_t(n);
  }
  ssize_t write(const char* ptr, size_t size) override {
    const auto deadline = Clock::now() + kWriteTimeout;
    for (;;) {
      const ssize_t n = ::send(sock_, ptr, size, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n >= 0) return n;
      if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) return -1;
      if (!wait(POLLOUT, deadline)) return -1;
    }
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override { address(true, ip, port); }
  void get_local_ip_and_port(std::string& ip, int& port) const override { address(false, ip, port); }
  socket_t socket() const override { return sock_; }

 private:
  // Waits until the socket is ready for `events` (or failed: the next call reports it); false at
  // the deadline or when the server stops.
  bool wait(short events, Clock::time_point deadline) const {
    for (;;) {
      const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now());
      if (server_.stopping() || left.count() <= 0) return false;
      pollfd p{sock_, events, 0};
      const int r = ::poll(&p, 1, int(std::min(left, kPollSlice).count()));
      if (r > 0) return true;
      if (r < 0 && errno != EINTR) return false;
    }
  }
  void address(bool remote, std::string& ip, int& port) const {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    auto* sa = reinterpret_cast<sockaddr*>(&a);
    if ((remote ? ::getpeername(sock_, sa, &len) : ::getsockname(sock_, sa, &len)) != 0) return;
    char host[NI_MAXHOST], serv[NI_MAXSERV];
    if (::getnameinfo(sa, len, host, sizeof host, serv, sizeof serv, NI_NUMERICHOST | NI_NUMERICSERV) != 0)
      return;
    ip = host;
    port = std::atoi(serv);
  }
  socket_t sock_;
  const LiveServer& server_;
  Clock::time_point read_deadline_;
  char buf_[4096];
  size_t off_ = 0, len_ = 0, received_ = 0;
};

bool LiveServer::process_and_close_socket(socket_t sock) {
  bool ok = false;
  if (t_over_capacity) {
    static constexpr std::string_view kBusy =
        "HTTP/1.1 503 Service Unavailable\r\nRetry-After: 1\r\nContent-Length: 0\r\nConnection: "
        "close\r\n\r\n";
    ::send(sock, kBusy.data(), kBusy.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
  } else {
    try {
      ConnectionStream strm(sock, *this);
      bool closed = false;
      ok = process_request(strm, /*close_connection=*/true, closed,
                           [](httplib::Request& req) { req.ranges.clear(); });
    } catch (const std::exception& e) {  // no exception may end the connection's thread
      spdlog::debug("live view: a request failed: {}", e.what());
    } catch (...) {
      spdlog::debug("live view: a request failed");
    }
  }
  ::shutdown(sock, SHUT_RDWR);
  ::close(sock);
  return ok;
}

// Whether `given` is `want`, in time that does not depend on where they differ (only on their
// lengths, which are public: a token is 32 hex digits), so that a client cannot guess a token byte
// by byte from the answers' timing.
bool same_token(std::string_view given, std::string_view want) {
  volatile unsigned char diff = given.size() == want.size() ? 0 : 1;
  for (size_t i = 0; i < want.size(); ++i)
    diff = diff | static_cast<unsigned char>(want[i] ^ (i < given.size() ? given[i] : 0));
  return diff == 0;
}

// The addresses of this machine's network interfaces at which a server on a wildcard address
// (0.0.0.0: IPv4 only; ::, ipv6_too: IPv4 and IPv6) can be reached from the network: not loopback,
// not IPv6 link-local (which needs a zone in a URL).
std::vector<std::string> interface_addresses(bool ipv6_too) {
  std::vector<std::string> out;
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) != 0) return out;
  for (const ifaddrs* i = list; i; i = i->ifa_next) {
    if (!i->ifa_addr) continue;
    const int family = i->ifa_addr->sa_family;
    if (family != AF_INET && !(ipv6_too && family == AF_INET6)) continue;
    if (family == AF_INET6 &&
        IN6_IS_ADDR_LINKLOCAL(&reinterpret_cast<const sockaddr_in6*>(i->ifa_addr)->sin6_addr))
      continue;
    char host[NI_MAXHOST];
    const socklen_t len = family == AF_INET ? sizeof(sockaddr_in) : sizeof(sockaddr_in6);
    if (::getnameinfo(i->ifa_addr, len, host, sizeof host, nullptr, 0, NI_NUMERICHOST) != 0) continue;
    if (!is_loopback_address(host) && std::find(out.begin(), out.end(), host) == out.end())
      out.push_back(host);
  }
  ::freeifaddrs(list);
  return out;
}

// "http://HOST:PORT/" (IPv6 in brackets).
std::string http_url(const std::string& host, int port) {
  return host.find(':') == std::string::npos ? fmt::format("http://{}:{}/", host, port)
                                             : fmt::format("http://[{}]:{}/", host, port);
}

// The live view (sinks.h). The page and its viewer are files of web/, embedded at build time
// (web_assets.h).
class HttpSink : public Sink {
 public:
  HttpSink(const std::string& host, int port, cv::Size size, const SinkOptions& opt)
      : host_(host == "localhost" ? "127.0.0.1" : host),
        port_(port),
        quality_(opt.jpeg_quality),
        max_streams_(opt.max_streams) {
    const bool loopback = is_loopback_address(host_);
    if (opt.token == TokenMode::kRandom || (opt.token == TokenMode::kAuto && !loopback)) {
      try {
        token_ = random_token();
      } catch (const std::exception& e) {  // std::random_device without a source of entropy
        throw SinkError(std::string("live view: cannot make a token: ") + e.what());
      }
    }
    if (max_streams_ < 1 || max_streams_ > kMaxStreams)
      throw SinkError(
          fmt::format("live view: the stream limit must be 1-{}, got {}", kMaxStreams, max_streams_));
    config_ = nlohmann::json{{"projection", to_string(opt.projection)},
                             {"width", size.width},
                             {"height", size.height},
                             {"max_streams", max_streams_},
                             {"viewer", viewer_embedded()}}
                  .dump();
    // A thread per connection up to the cap, streams at most max_streams of them (LiveServer).
    const size_t cap = size_t(max_streams_) + kOtherConnections;
    server_.new_task_queue = [cap] { return new ConnectionThreads(cap); };
    // No bodies: methods other than GET and HEAD, and requests with a body, are refused from their
    // headers.
    server_.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
      if (req.method != "GET" && req.method != "HEAD") {
        res.status = 405;
        res.set_header("Allow", "GET, HEAD");
        res.set_content("omma live view: GET only", "text/plain");
        return httplib::Server::HandlerResponse::Handled;
      }
      if (req.has_header("Transfer-Encoding") ||
          (req.has_header("Content-Length") && req.get_header_value("Content-Length") != "0")) {
        res.status = 413;
        res.set_content("omma live view: requests take no body", "text/plain");
        return httplib::Server::HandlerResponse::Handled;
      }
      // The token, where one is required: everything but the viewer's own files (the same for every
      // omma) needs it.
      if (!token_.empty() && req.path.rfind("/viewer/", 0) != 0 && req.path != "/favicon.ico" &&
          !same_token(req.get_param_value("token"), token_)) {
        res.status = 403;
        res.set_content(
            "omma live view: this address needs its token (the URL with ?token=... that omma run "
            "printed)",
            "text/plain");
        return httplib::Server::HandlerResponse::Handled;
      }
      return httplib::Server::HandlerResponse::Unhandled;
    });
    // The page's URL holds the token: no Referer carries it to another site.
    server_.set_post_routing_handler([](const httplib::Request&, httplib::Response& res) {
      res.set_header("Referrer-Policy", "no-referrer");
    });
    server_.set_expect_100_continue_handler([](const httplib::Request& req, httplib::Response& res) {
      if (req.method == "GET" || req.method == "HEAD") return 100;
      res.status = 405;
      res.set_header("Allow", "GET, HEAD");
      return 405;
    });
    server_.set_payload_max_length(kMaxRequestBytes);
    server_.Get("/", [](const httplib::Request&, httplib::Response& res) { serve_asset("/live.html", res); });
    server_.Get(R"(/viewer/([A-Za-z0-9_.-]+))", [](const httplib::Request& req, httplib::Response& res) {
      serve_asset(fmt::format("/{}", std::string(req.matches[1])), res);  // (fmt: GCC 12 -Wrestrict)
    });
    server_.Get("/favicon.ico", [](const httplib::Request&, httplib::Response& res) { res.status = 204; });
    server_.Get("/config.json", [this](const httplib::Request&, httplib::Response& res) {
      res.set_content(config_, "application/json");
    });
    server_.Get("/stats.json", [this](const httplib::Request&, httplib::Response& res) {
      res.set_header("Cache-Control", "no-cache");
      std::lock_guard<std::mutex> lock(mutex_);
      res.set_content(stats_.dump(), "application/json");
    });
    server_.Get("/frame.jpg", [this](const httplib::Request&, httplib::Response& res) {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait_for(lock, std::chrono::seconds(2), [&] { return seq_ > 0 || stopping_; });
      if (jpeg_.empty()) {
        res.status = 503;
        res.set_content("no frame yet", "text/plain");
        return;
      }
      res.set_header("Cache-Control", "no-cache");
      res.set_content(std::string(jpeg_.begin(), jpeg_.end()), "image/jpeg");
    });
    server_.Get("/stream.mjpg", [this](const httplib::Request&, httplib::Response& res) {
      if (streams_.fetch_add(1) >= max_streams_) {
        streams_.fetch_sub(1);
        res.status = 503;
        res.set_header("Retry-After", "5");
        res.set_content(
            fmt::format("omma live view: {} viewers are streaming already (the limit)", max_streams_),
            "text/plain");
        return;
      }
      auto last = std::make_shared<long>(0);
      res.set_header("Cache-Control", "no-cache");
      res.set_chunked_content_provider(
          "multipart/x-mixed-replace; boundary=ommaframe",
          [this, last](size_t, httplib::DataSink& sink) {
            std::vector<uchar> jpeg;
            {
              std::unique_lock<std::mutex> lock(mutex_);
              cv_.wait_for(lock, std::chrono::milliseconds(500), [&] { return seq_ > *last || stopping_; });
              if (stopping_) {
                sink.done();
                return false;
              }
              if (seq_ == *last) return sink.is_writable();  // nothing new yet; keep a live connection
              *last = seq_;
              jpeg = jpeg_;
            }
            const std::string head =
                "--ommaframe\r\nContent-Type: image/jpeg\r\nContent-Length: " + std::to_string(jpeg.size()) +
                "\r\n\r\n";
            if (!sink.write(head.data(), head.size())) return false;
            if (!sink.write(reinterpret_cast<const char*>(jpeg.data()), jpeg.size())) return false;
            return sink.write("\r\n", 2);
          },
          [this](bool) { streams_.fetch_sub(1); });
    });
    server_.set_keep_alive_max_count(1);
    // SO_REUSEADDR only: httplib's default also sets SO_REUSEPORT, which would let a second server
    // bind a port that is already in use.
    server_.set_socket_options([](socket_t sock) {
      int yes = 1;
      setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, reinterpret_cast<const void*>(&yes), sizeof(yes));
    });
    if (!server_.bind_to_port(host_.c_str(), port))
      throw SinkError(
          fmt::format("cannot serve the live view on {}:{} (port in use, address not of this "
                      "machine, or not permitted)",
                      host_, port));
    server_.widen_backlog();
    thread_ = std::thread([this] {
      try {
        server_.listen_after_bind();
      } catch (const std::exception& e) {
        spdlog::error("live view on {}:{} stopped: {}", host_, port_, e.what());
      }
      listen_ended_ = true;
    });
    try {
      encoder_ = std::thread([this] { encode(); });
    } catch (...) {
      stop();
      throw;
    }
    announce(loopback);
  }
  ~HttpSink() override { stop(); }
  // The panorama is JPEG-encoded in the sink's own thread, so that encoding never slows the render
  // loop; if the encoder is still busy with the previous panorama, the newer one replaces it.
  void write(const cv::Mat& pano, const render::FrameStore&) override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      pano.copyTo(pending_);
      has_pending_ = true;
    }
    cv_.notify_all();
  }
  void set_stats(const nlohmann::json& s) override {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_ = s;
    stats_["viewers"] = streams_.load();
  }
  void finish() override { stop(); }
  void abort() override { stop(); }
  // The URL without its token (the summary is no place for it).
  std::string describe() const override {
    return http_url(host_, port_) + (token_.empty() ? "" : " (with its token)");
  }

 private:
  static constexpr int kMaxStreams = 256;  // each stream is a thread
  // Logs where the live view can be opened: the URL with its token, on the wildcards one per
  // network interface; a warning first if the network can see it. With a token at warning level, so
  // that --quiet still shows the one URL that opens the page.
  void announce(bool loopback) const {
    if (!loopback)
      spdlog::warn("live view on {}: the panorama is visible to the network: {}", http_url(host_, port_),
                   token_.empty() ? "anyone who can reach this port can watch it (--token none)"
                                  : "anyone who has the URL with its token can watch it");
    std::vector<std::string> hosts;
    if (host_ == "0.0.0.0" || host_ == "::") hosts = interface_addresses(host_ == "::");
    if (hosts.empty()) hosts.push_back(host_);
    for (const auto& h : hosts) {
      const std::string url = http_url(h, port_) + (token_.empty() ? "" : "?token=" + token_);
      if (token_.empty())
        spdlog::info("live view: {}", url);
      else
        spdlog::warn("live view: {}", url);
    }
  }
  static void serve_asset(const std::string& path, httplib::Response& res) {
    const WebAsset* a = find_web_asset(path);
    if (!a) {
      res.status = 404;
      return;
    }
    res.set_content(std::string(a->data), std::string(a->type));
  }
  void encode() {
    cv::Mat pano;
    std::vector<uchar> buf;
    for (;;) {
      {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait(lock, [&] { return has_pending_ || stopping_; });
        if (stopping_) return;
        cv::swap(pano, pending_);
        has_pending_ = false;
      }
      cv::imencode(".jpg", pano, buf, {cv::IMWRITE_JPEG_QUALITY, quality_});
      {
        std::lock_guard<std::mutex> lock(mutex_);
        jpeg_.swap(buf);
        ++seq_;
      }
      cv_.notify_all();
    }
  }
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_) return;
      stopping_ = true;
    }
    cv_.notify_all();
    // Server::stop() does nothing before the server runs: wait for that (or for its thread's end).
    while (thread_.joinable() && !listen_ended_ && !server_.is_running())
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    server_.stop();  // ends the accepting loop, which joins every connection's thread
    if (thread_.joinable()) thread_.join();
    if (encoder_.joinable()) encoder_.join();
  }
  std::string host_;   // the address it listens on
  std::string token_;  // required in every URL but the viewer's files; empty: none
  int port_, quality_, max_streams_;
  std::string config_;
  LiveServer server_;
  std::thread thread_, encoder_;
  std::atomic<bool> listen_ended_{false};
  std::mutex mutex_;
  std::condition_variable cv_;
  cv::Mat pending_;  // the newest panorama, not encoded yet
  bool has_pending_ = false;
  std::vector<uchar> jpeg_;  // the newest encoded one, number seq_
  long seq_ = 0;
  bool stopping_ = false;
  std::atomic<int> streams_{0};
  nlohmann::json stats_ = nlohmann::json::object();
};

}  // namespace

int parse_port(const std::string& spec, const std::string& text) {
  try {
    size_t pos = 0;
    const int p = std::stoi(text, &pos);
    if (pos == text.size() && p > 0 && p < 65536) return p;
  } catch (const std::exception&) {
  }
  throw SinkError("sink '" + spec + "': port '" + text + "': expected a port number 1-65535");
}

bool SinkOptions::IsValid(std::string* why) const {
  if (!valid_rate(fps, false)) return invalid(why, fmt::format("fps must be {}..{}", kMinRate, kMaxRate));
  if (jpeg_quality < 1 || jpeg_quality > 100) return invalid(why, "jpeg quality must be 1..100");
  if (max_streams < 1) return invalid(why, "max streams must be >= 1");
  in_addr a4{};
  in6_addr a6{};
  if (bind != "localhost" && ::inet_pton(AF_INET, bind.c_str(), &a4) != 1 &&
      ::inet_pton(AF_INET6, bind.c_str(), &a6) != 1)
    return invalid(why, "live view address '" + bind +
                            "': expected a numeric IPv4 or IPv6 address (0.0.0.0 or :: for every interface) "
                            "or localhost");
  // Video files' own options (their rate is `fps`, checked by the writer: at most 1000 frames/s).
  if (io::VideoOptions v = video; v.fps = 30, !v.IsValid(why)) return false;
  return true;
}

bool is_loopback_address(const std::string& address) {
  if (address == "localhost") return true;
  in_addr a4{};
  if (::inet_pton(AF_INET, address.c_str(), &a4) == 1) return (ntohl(a4.s_addr) >> 24) == 127;
  in6_addr a6{};
  if (::inet_pton(AF_INET6, address.c_str(), &a6) != 1) return false;
  return IN6_IS_ADDR_LOOPBACK(&a6) || (IN6_IS_ADDR_V4MAPPED(&a6) && a6.s6_addr[12] == 127);
}

std::string random_token() {
  std::random_device rd;  // the system's entropy (Linux: getrandom, /dev/urandom or RDRAND)
  static_assert(std::random_device::max() >= 0xffffffffu, "32 bits per draw");
  std::string token;
  for (int i = 0; i < 4; ++i) token += fmt::format("{:08x}", uint32_t(rd() & 0xffffffffu));
  return token;
}

TokenMode parse_token_mode(const std::string& text) {
  if (text == "auto") return TokenMode::kAuto;
  if (text == "random") return TokenMode::kRandom;
  if (text == "none") return TokenMode::kNone;
  throw std::invalid_argument("--token '" + text + "': expected auto, random or none");
}

std::unique_ptr<Sink> open_sink(const std::string& spec, const Rig& rig, cv::Size pano_size,
                                const SinkOptions& opt) {
  if (std::string why; !opt.IsValid(&why)) throw SinkError("sink '" + spec + "': " + why);
  if (spec.rfind("rtsp://", 0) == 0 || spec.rfind("srt://", 0) == 0)
    return open_gst_sink(spec, pano_size, opt);  // gst.h
  if (spec.rfind("http://", 0) == 0) {
    // http://HOST:PORT: HOST is the address to serve on (as --bind; IPv6 in brackets).
    std::string rest = spec.substr(7);
    if (!rest.empty() && rest.back() == '/') rest.pop_back();
    const size_t colon = rest.rfind(':');
    if (colon == std::string::npos) throw SinkError("sink '" + spec + "': expected http://ADDRESS:PORT");
    std::string host = rest.substr(0, colon);
    if (host.size() >= 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
    SinkOptions at = opt;
    at.bind = host;
    if (std::string why; !at.IsValid(&why)) throw SinkError("sink '" + spec + "': " + why);
    const SinkOptions defaults;
    if (opt.bind != defaults.bind && opt.bind != host)
      throw SinkError("sink '" + spec + "': serves on " + host + ", but the live view's address is " +
                      opt.bind + " (--bind): give one of them");
    return std::make_unique<HttpSink>(host, parse_port(spec, rest.substr(colon + 1)), pano_size, at);
  }
  if (spec.rfind("http:", 0) == 0)
    return std::make_unique<HttpSink>(opt.bind, parse_port(spec, spec.substr(5)), pano_size, opt);
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
  if (spec == "-") return std::make_unique<StdoutSink>(pano_size, opt.fps);
  if (io::is_video_path(spec)) {
    io::VideoOptions vo = opt.video;
    vo.fps = opt.fps;
    return std::make_unique<VideoSink>(spec, pano_size, vo, metadata);
  }
  throw SinkError(
      "sink '" + spec +
      "': use FILE.mp4|.mov|.mkv|.webm|.avi, - (raw frames on stdout), png:DIR, DIR/, cam:ID:SINK, "
      "http:PORT, rtsp://HOST:PORT/PATH or srt://HOST:PORT");
}

}  // namespace omma::live
