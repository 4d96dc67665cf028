// The live view (HttpSink) under hostile clients on loopback. It listens on 127.0.0.1 only, but any
// web page the user visits can reach it. All at once: 50 idle connections, 12 slowloris connections
// (one header byte every 300 ms; both kinds reopened as soon as the server drops them), every
// stream taken, 12 multi-range requests on /frame.jpg and a 1 MB POST. The stats must still answer
// within a second, no response may be larger than the frame it serves, no body is read, memory
// stays bounded, and stopping the sink with a slowloris client connected stays quick.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Core>  // before <httplib.h>, whose <resolv.h> defines _res, a name Eigen uses
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include "omma/live/sinks.h"
#include "omma/testing/net.h"
#include "omma/testing/synthetic.h"

namespace omma::live {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

long rss_kb() {
  std::ifstream f("/proc/self/status");
  for (std::string line; std::getline(f, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

// The live view on a free loopback port (*port), or null after five ports that were taken meanwhile.
std::unique_ptr<Sink> open_http_sink(const Rig& rig, cv::Size size, const SinkOptions& opt, int* port) {
  for (int attempt = 0; attempt < 5; ++attempt) {
    *port = testing::free_port();
    try {
      return open_sink("http:" + std::to_string(*port), rig, size, opt);
    } catch (const SinkError&) {
    }
  }
  return nullptr;
}

// A non-blocking connection to 127.0.0.1:port (connect itself waits at most 2 s); -1 if refused.
int connect_to(int port) {
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  timeval tv{2, 0};
  ::setsockopt(s, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(uint16_t(port));
  if (::connect(s, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(s);
    return -1;
  }
  ::fcntl(s, F_SETFL, ::fcntl(s, F_GETFL) | O_NONBLOCK);
  return s;
}

bool send_all(int fd, const std::string& s) {
  return ::send(fd, s.data(), s.size(), MSG_NOSIGNAL) == ssize_t(s.size());
}

// The hostile clients, all driven by one poll() loop.
struct Attack {
  enum Kind { kIdle, kSlow, kStream, kRange };
  struct Conn {
    explicit Conn(Kind k) : kind(k) {}
    Kind kind;
    int fd = -1;
    Clock::time_point opened, next_byte;
    size_t bytes = 0;
    std::string head;   // the response's first bytes
    bool first = true;  // of the connections opened at the start
  };
  int port;
  std::string range_request;
  std::vector<Conn> conns;
  // Results.
  std::atomic<bool> all_open{false};
  long peak_rss_kb = 0;
  std::vector<double> first_idle_life_s, first_slow_life_s;  // until the server dropped them
  std::vector<size_t> range_bytes;                           // whole responses (headers + body)
  std::vector<std::string> range_heads;
  int streams_ok = 0, streams_ended = 0, reopened = 0;
  size_t min_stream_bytes = 0;

  static constexpr const char* kSlowHead = "GET /stats.json HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ";

  void open(Conn& c) {
    c.fd = connect_to(port);
    c.opened = Clock::now();
    c.next_byte = c.opened + milliseconds(300);
    c.bytes = 0;
    c.head.clear();
    if (c.fd < 0) return;
    if (c.kind == kSlow) send_all(c.fd, kSlowHead);
    if (c.kind == kStream) send_all(c.fd, "GET /stream.mjpg HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
    if (c.kind == kRange) send_all(c.fd, range_request);
  }

  void run(int idle, int slow, int streams, int ranges, double seconds) {
    std::string spec = "bytes=0-";
    while (spec.size() < 3000) spec += ",0-";
    range_request = "GET /frame.jpg HTTP/1.1\r\nHost: 127.0.0.1\r\nRange: " + spec + "\r\n\r\n";
    for (auto [kind, n] : {std::pair{kStream, streams}, {kRange, ranges}, {kIdle, idle}, {kSlow, slow}})
      for (int i = 0; i < n; ++i) conns.emplace_back(kind);
    for (auto& c : conns) open(c);
    all_open = true;
    const auto t0 = Clock::now();
    auto next_rss = t0;
    std::vector<char> buf(1 << 16);
    while (seconds_since(t0) < seconds) {
      std::vector<pollfd> fds;
      for (auto& c : conns) fds.push_back(pollfd{c.fd, POLLIN, 0});  // fd -1: ignored
      ::poll(fds.data(), fds.size(), 20);
      const auto now = Clock::now();
      for (size_t i = 0; i < conns.size(); ++i) {
        Conn& c = conns[i];
        if (c.fd < 0) continue;
        bool closed = false;
        if (fds[i].revents) {
          for (;;) {
            const ssize_t n = ::recv(c.fd, buf.data(), buf.size(), 0);
            if (n > 0) {
              if (c.head.size() < 64)
                c.head.append(buf.data(), std::min<size_t>(size_t(n), 64 - c.head.size()));
              c.bytes += size_t(n);
              continue;
            }
            closed = n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK);
            break;
          }
        }
        if (!closed && c.kind == kSlow && now >= c.next_byte) {
          closed = ::send(c.fd, "a", 1, MSG_NOSIGNAL) != 1;
          c.next_byte += milliseconds(300);
        }
        if (!closed) continue;
        const double life = std::chrono::duration<double>(now - c.opened).count();
        if (c.first && c.kind == kIdle) first_idle_life_s.push_back(life);
        if (c.first && c.kind == kSlow) first_slow_life_s.push_back(life);
        if (c.kind == kRange) {
          range_bytes.push_back(c.bytes);
          range_heads.push_back(c.head);
        }
        if (c.kind == kStream) ++streams_ended;
        ::close(c.fd);
        c.fd = -1;
        c.first = false;
        if (c.kind == kIdle || c.kind == kSlow) {  // keep the pressure up
          open(c);
          ++reopened;
        }
      }
      if (now >= next_rss) {
        peak_rss_kb = std::max(peak_rss_kb, rss_kb());
        next_rss = now + milliseconds(50);
      }
    }
    min_stream_bytes = SIZE_MAX;
    for (auto& c : conns) {
      if (c.kind == kStream) {
        streams_ok += c.head.find(" 200 ") != std::string::npos;
        min_stream_bytes = std::min(min_stream_bytes, c.bytes);
      }
      if (c.fd >= 0) ::close(c.fd);
      c.fd = -1;
    }
  }
};

// A POST of `length` bytes: the status the server answered with after the headers, before any of
// the body was sent (0: no answer within a second).
int post_status_before_body(int port, size_t length) {
  const int fd = connect_to(port);
  if (fd < 0) return -1;
  send_all(fd,
           "POST /stats.json HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/octet-stream\r\n"
           "Content-Length: " +
               std::to_string(length) + "\r\n\r\n");
  pollfd p{fd, POLLIN, 0};
  int status = 0;
  if (::poll(&p, 1, 1000) == 1) {
    char buf[64] = {};
    const ssize_t n = ::recv(fd, buf, sizeof buf - 1, 0);
    if (n > 12 && std::string(buf, 9) == "HTTP/1.1 ") status = std::atoi(buf + 9);
  }
  if (status == 0) {  // the server waits for the body: send it, a megabyte
    const std::string body(length, 'x');
    size_t sent = 0;
    const auto t0 = Clock::now();
    while (sent < body.size() && seconds_since(t0) < 2) {
      const ssize_t n = ::send(fd, body.data() + sent, body.size() - sent, MSG_NOSIGNAL);
      if (n > 0)
        sent += size_t(n);
      else if (errno != EAGAIN)
        break;
      else
        std::this_thread::sleep_for(milliseconds(1));
    }
  }
  ::close(fd);
  return status;
}

TEST(HttpHostile, StatsAnswerWithinASecondAndMemoryStaysBoundedUnderHostileClients) {
  const Rig rig = testing::test_rig_24(64, 64);
  SinkOptions opt;
  opt.jpeg_quality = 80;
  const cv::Size size(512, 256);
  cv::Mat pano = cv::imread(std::string(OMMA_DATA_DIR) + "/lake.jpg", cv::IMREAD_COLOR);
  ASSERT_FALSE(pano.empty());
  cv::resize(pano, pano, size, 0, 0, cv::INTER_AREA);
  int port = 0;
  std::unique_ptr<Sink> sink = open_http_sink(rig, size, opt, &port);
  ASSERT_TRUE(sink) << "no free port";
  // The render loop: the same panorama (so every frame has the same size) at 30 fps, and stats.
  std::atomic<bool> feeding{true};
  std::thread feeder([&] {
    const render::FrameStore store;
    for (long n = 0; feeding; ++n) {
      sink->write(pano, store);
      sink->set_stats(nlohmann::json{{"frames", n}, {"fps", 30.0}});
      std::this_thread::sleep_for(milliseconds(33));
    }
  });
  struct Stop {  // also when an assertion returns early
    std::atomic<bool>& feeding;
    std::thread& t;
    ~Stop() {
      feeding = false;
      if (t.joinable()) t.join();
    }
  } stop_feeder{feeding, feeder};

  // The frame, its size, and a warm server (a stream, the stats) before the baseline.
  size_t frame_bytes = 0;
  {
    httplib::Client cli("127.0.0.1", port);
    cli.set_read_timeout(3, 0);
    auto res = cli.Get("/frame.jpg");
    ASSERT_TRUE(res);
    ASSERT_EQ(res->status, 200);
    frame_bytes = res->body.size();
    ASSERT_TRUE(cli.Get("/stats.json"));
    int parts = 0;
    cli.Get("/stream.mjpg", [&](const char*, size_t) { return ++parts < 20; });
  }
  std::this_thread::sleep_for(milliseconds(200));
  const long rss0_kb = rss_kb();

  Attack attack;
  attack.port = port;
  const int idle = 50, slow = 12, ranges = 12;
  std::thread attacker([&] { attack.run(idle, slow, opt.max_streams, ranges, 5.0); });
  while (!attack.all_open) std::this_thread::sleep_for(milliseconds(10));
  std::this_thread::sleep_for(milliseconds(300));
  std::vector<double> stats_s;
  int stats_ok = 0, post_status = -1;
  const int probes = 8;
  for (int i = 0; i < probes; ++i) {
    httplib::Client cli("127.0.0.1", port);
    cli.set_connection_timeout(2, 0);
    cli.set_read_timeout(1, 500000);
    const auto t0 = Clock::now();
    auto res = cli.Get("/stats.json");
    stats_s.push_back(seconds_since(t0));
    stats_ok += res && res->status == 200 && res->body.find("\"frames\"") != std::string::npos;
    if (i == probes / 2) post_status = post_status_before_body(port, 1 << 20);
    std::this_thread::sleep_for(milliseconds(400));
  }
  attacker.join();

  // Stopping with a slowloris client connected (trickling for at most 3 s more).
  std::atomic<bool> trickling{true};
  std::thread trickler([&] {
    const int fd = connect_to(port);
    if (fd < 0) return;
    send_all(fd, Attack::kSlowHead);
    for (int i = 0; i < 10 && trickling; ++i) {
      std::this_thread::sleep_for(milliseconds(300));
      if (::send(fd, "a", 1, MSG_NOSIGNAL) != 1) break;
    }
    ::close(fd);
  });
  std::this_thread::sleep_for(milliseconds(200));
  feeding = false;
  feeder.join();
  const auto t_stop = Clock::now();
  sink.reset();
  const double stop_s = seconds_since(t_stop);
  trickling = false;
  trickler.join();

  const double worst_stats_s = *std::max_element(stats_s.begin(), stats_s.end());
  const size_t worst_range = attack.range_bytes.empty()
                                 ? 0
                                 : *std::max_element(attack.range_bytes.begin(), attack.range_bytes.end());
  const double worst_idle_s =
      attack.first_idle_life_s.empty()
          ? 0
          : *std::max_element(attack.first_idle_life_s.begin(), attack.first_idle_life_s.end());
  const double growth_mb = (attack.peak_rss_kb - rss0_kb) / 1024.0;
  std::string stats_list;
  for (double s : stats_s) stats_list += fmt::format(" {:.3f}", s);
  std::printf(
      "  under attack: /stats.json %d/%d answered, seconds:%s\n"
      "  idle connections dropped by the server: %zu/%d of the first (latest after %.2f s); slowloris "
      "%zu/%d; "
      "%d reopened\n"
      "  streams: %d/%d playing, %d ended, >= %zu bytes each\n"
      "  multi-range (%zu-byte request): %zu/%d answered, largest %zu bytes (frame %zu bytes), first: %.12s\n"
      "  1 MB POST: status %d before the body\n"
      "  resident memory: %.1f MB before, peak %.1f MB (+%.1f MB); stop() with a slowloris client: %.2f s\n",
      stats_ok, probes, stats_list.c_str(), attack.first_idle_life_s.size(), idle, worst_idle_s,
      attack.first_slow_life_s.size(), slow, attack.reopened, attack.streams_ok, opt.max_streams,
      attack.streams_ended, attack.min_stream_bytes, attack.range_request.size(), attack.range_bytes.size(),
      ranges, worst_range, frame_bytes, attack.range_heads.empty() ? "" : attack.range_heads[0].c_str(),
      post_status, rss0_kb / 1024.0, attack.peak_rss_kb / 1024.0, growth_mb, stop_s);

  // The stats answer within a second, every time.
  EXPECT_EQ(stats_ok, probes);
  EXPECT_LT(worst_stats_s, 1.0);
  // Idle and trickling connections let go of their thread within ~2 s (the request deadline).
  EXPECT_EQ(attack.first_idle_life_s.size(), size_t(idle));
  EXPECT_LT(worst_idle_s, 3.0);
  EXPECT_EQ(attack.first_slow_life_s.size(), size_t(slow));
  // Every stream plays (the streams take no place from the page) and none was dropped.
  EXPECT_EQ(attack.streams_ok, opt.max_streams);
  EXPECT_EQ(attack.streams_ended, 0);
  EXPECT_GT(attack.min_stream_bytes, 2 * frame_bytes);
  // A multi-range request gets the frame once at most (or 416), never one copy per range.
  EXPECT_EQ(attack.range_bytes.size(), size_t(ranges));
  EXPECT_LE(worst_range, frame_bytes + 1024);
  // A POST is refused from its headers, before the body is sent.
  EXPECT_TRUE(post_status == 405 || post_status == 413) << post_status;
  // Memory: the attack may hold ~100 connection threads (stack pages touched, a request of at most
  // 16 kB each), 12 single frames and 8 streams' frame buffers: ~10 MB; 64 MB leaves room for the
  // allocator's per-thread arenas. (Amplified ranges and buffered bodies cost hundreds of MB.)
  EXPECT_LT(growth_mb, 64.0);
  // stop() does not wait on a client that trickles its request.
  EXPECT_LT(stop_s, 2.0);
}

// Past the connection cap (max_streams + 256) a new connection is answered 503 at once; the idle
// ones that fill the server are dropped after the request deadline (2 s), and then it answers again.
// Oversized and pathological requests get a bounded answer and leave the server serving.
TEST(HttpHostile, PastTheConnectionCapNewConnectionsGet503UntilTheIdleOnesAreDropped) {
  const Rig rig = testing::test_rig_24(64, 64);
  SinkOptions opt;
  opt.max_streams = 1;
  const int cap = opt.max_streams + 256;
  const cv::Size size(256, 128);
  int port = 0;
  std::unique_ptr<Sink> sink = open_http_sink(rig, size, opt, &port);
  ASSERT_TRUE(sink) << "no free port";
  cv::Mat pano(size, CV_8UC3, cv::Scalar(40, 90, 160));
  sink->write(pano, render::FrameStore());
  sink->set_stats(nlohmann::json{{"frames", 1}});
  // A Range header as long as httplib takes one (8 kB a header line).
  std::string ranges = "bytes=0-";
  while (ranges.size() < 8150) ranges += ",0-";
  {
    httplib::Client cli("127.0.0.1", port);
    cli.set_read_timeout(3, 0);
    auto frame = cli.Get("/frame.jpg");
    ASSERT_TRUE(frame);
    auto res = cli.Get("/frame.jpg", {{"Range", ranges}});
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 200);
    EXPECT_EQ(res->body.size(), frame->body.size());
    // Larger than that: refused.
    res = cli.Get("/stats.json", {{"X-Big", std::string(20000, 'a')}});
    EXPECT_TRUE(!res || res->status == 400) << res->status;
    res = cli.Get("/stats.json");
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 200);
  }
  // Fill the server with idle connections, and some more.
  std::vector<int> idle;
  for (int i = 0; i < cap + 20; ++i) idle.push_back(connect_to(port));
  std::this_thread::sleep_for(milliseconds(200));
  int refused = 0, unanswered = 0;
  for (int fd : idle) {
    char buf[64] = {};
    const ssize_t n = ::recv(fd, buf, sizeof buf - 1, 0);
    if (n > 0 && std::string(buf).find(" 503 ") != std::string::npos) ++refused;
    if (n < 0 && errno == EAGAIN) ++unanswered;
  }
  std::printf("  %d idle connections: %d held, %d refused 503 at once\n", cap + 20, unanswered, refused);
  EXPECT_EQ(unanswered, cap);
  EXPECT_EQ(refused, 20);
  // The page's own request is refused too while the server is full, but answered once the idle
  // connections have been dropped.
  const auto t0 = Clock::now();
  double answered_s = -1;
  while (seconds_since(t0) < 5 && answered_s < 0) {
    httplib::Client cli("127.0.0.1", port);
    cli.set_read_timeout(1, 0);
    auto res = cli.Get("/stats.json");
    if (res && res->status == 200) answered_s = seconds_since(t0);
    if (answered_s < 0) std::this_thread::sleep_for(milliseconds(100));
  }
  std::printf("  /stats.json answered again after %.2f s\n", answered_s);
  EXPECT_GE(answered_s, 0);
  EXPECT_LT(answered_s, 3.0);
  for (int fd : idle)
    if (fd >= 0) ::close(fd);
}

// What is and is not loopback (only a loopback address serves without a token by default), the
// addresses --bind takes, the tokens and the token modes.
TEST(LiveViewAddress, LoopbackIsRecognisedAndBadAddressesAreRefused) {
  for (const char* a : {"127.0.0.1", "127.1.2.3", "127.255.255.254", "::1", "::ffff:127.0.0.1", "localhost"})
    EXPECT_TRUE(is_loopback_address(a)) << a;
  for (const char* a : {"0.0.0.0", "::", "192.168.1.2", "10.0.0.1", "128.0.0.1", "126.255.255.255",
                        "::ffff:10.0.0.1", "fe80::1", "::2", "", "my.host", "127.0.0.1 ", "127.0.0.1:80"})
    EXPECT_FALSE(is_loopback_address(a)) << a;
  for (const char* a : {"127.0.0.1", "0.0.0.0", "::", "::1", "192.168.1.2", "localhost"}) {
    SinkOptions opt;
    opt.bind = a;
    std::string why;
    EXPECT_TRUE(opt.IsValid(&why)) << a << ": " << why;
  }
  for (const char* a : {"", "my.host", "256.0.0.1", "127.0.0.1:80", "[::1]", "fe80::1%eth0"}) {
    SinkOptions opt;
    opt.bind = a;
    std::string why;
    EXPECT_FALSE(opt.IsValid(&why)) << a;
    EXPECT_NE(why.find("address"), std::string::npos) << why;
    EXPECT_THROW(open_sink("http:1", testing::test_rig_24(64, 64), cv::Size(64, 64), opt), SinkError) << a;
  }
  std::set<std::string> tokens;
  for (int i = 0; i < 200; ++i) {
    const std::string t = random_token();
    EXPECT_EQ(t.size(), 32u);
    EXPECT_EQ(t.find_first_not_of("0123456789abcdef"), std::string::npos) << t;
    tokens.insert(t);
  }
  EXPECT_EQ(tokens.size(), 200u);
  EXPECT_EQ(parse_token_mode("auto"), TokenMode::kAuto);
  EXPECT_EQ(parse_token_mode("random"), TokenMode::kRandom);
  EXPECT_EQ(parse_token_mode("none"), TokenMode::kNone);
  EXPECT_THROW(parse_token_mode("secret"), std::invalid_argument);
}

// With a token required (--token random; the default off loopback), nothing but the viewer's own
// files answers without it: 403 before any frame or statistic is sent, also to a multi-range
// request, and still 405 / 413 for the other methods and bodies (checked first, from the headers).
// The token is the one logged; a wrong one of the same length is refused.
TEST(HttpHostile, WithATokenNothingButTheViewerFilesAnswersWithoutIt) {
  const Rig rig = testing::test_rig_24(64, 64);
  SinkOptions opt;
  opt.token = TokenMode::kRandom;
  auto log = std::make_shared<std::ostringstream>();
  auto log_sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(*log);
  spdlog::default_logger()->sinks().push_back(log_sink);
  int port = 0;
  std::unique_ptr<Sink> sink = open_http_sink(rig, cv::Size(128, 64), opt, &port);
  spdlog::default_logger()->sinks().pop_back();
  ASSERT_TRUE(sink) << "no free port";
  sink->write(cv::Mat(64, 128, CV_8UC3, cv::Scalar(40, 90, 160)), render::FrameStore());
  sink->set_stats(nlohmann::json{{"frames", 1}});
  const std::string logged = log->str();
  const std::string head = fmt::format("http://127.0.0.1:{}/?token=", port);
  const size_t at = logged.find(head);
  ASSERT_NE(at, std::string::npos) << logged;
  const std::string token = logged.substr(at + head.size(), 32);
  EXPECT_EQ(token.find_first_not_of("0123456789abcdef"), std::string::npos) << token;
  EXPECT_EQ(sink->describe().find(token), std::string::npos) << sink->describe();
  std::string wrong = token;
  wrong[0] = wrong[0] == 'a' ? 'b' : 'a';

  httplib::Client cli("127.0.0.1", port);
  cli.set_read_timeout(3, 0);
  for (const char* path : {"/", "/stats.json", "/config.json", "/frame.jpg", "/stream.mjpg", "/nothing"}) {
    for (const std::string& query :
         {std::string(), "?token=" + wrong, std::string("?token="), "?token=" + token + "0"}) {
      auto res = cli.Get(path + query);
      ASSERT_TRUE(res) << path << query;
      EXPECT_EQ(res->status, 403) << path << query;
      EXPECT_LT(res->body.size(), 200u) << path << query;
    }
  }
  auto ranged = cli.Get("/frame.jpg", {{"Range", "bytes=0-,0-,0-,0-"}});
  ASSERT_TRUE(ranged);
  EXPECT_EQ(ranged->status, 403);
  auto post = cli.Post("/stats.json?token=" + token, std::string(100000, 'x'), "text/plain");
  EXPECT_TRUE(!post || post->status == 405 || post->status == 413) << post->status;
  post = cli.Post("/stats.json", std::string(100000, 'x'), "text/plain");
  EXPECT_TRUE(!post || post->status == 405 || post->status == 413) << post->status;
  // The viewer's files need none; everything answers with it.
  for (const char* path : {"/viewer/live.js", "/favicon.ico"}) {
    auto res = cli.Get(path);
    ASSERT_TRUE(res) << path;
    EXPECT_LT(res->status, 300) << path;
  }
  for (const char* path : {"/", "/stats.json", "/config.json", "/frame.jpg"}) {
    auto res = cli.Get(std::string(path) + "?token=" + token);
    ASSERT_TRUE(res) << path;
    EXPECT_EQ(res->status, 200) << path;
    EXPECT_EQ(res->get_header_value("Referrer-Policy"), "no-referrer") << path;
  }
  int parts = 0;
  auto stream = cli.Get("/stream.mjpg?token=" + token, [&](const char*, size_t) { return ++parts < 3; });
  EXPECT_GE(parts, 3);
  EXPECT_EQ(nlohmann::json::parse(cli.Get("/stats.json?token=" + token)->body)["frames"], 1);
}

}  // namespace
}  // namespace omma::live
