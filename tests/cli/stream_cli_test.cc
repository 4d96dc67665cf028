// `omma run`'s network sinks (src/omma/live/gst.h) read back by outside tools while the run serves
// them: ffprobe (codec, size, rate, container) and ffmpeg (the decoded frames, compared with the PNG
// sink's panoramas of the same run). The scene is static (frames:DIR, stills), so every panorama is
// the same and any decoded frame can be compared with any PNG frame. Only 127.0.0.1 is used.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "omma/testing/net.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

bool have(const std::string& tool) {
  return std::system(("command -v " + tool + " >/dev/null 2>&1").c_str()) == 0;
}

bool running(pid_t pid) { return ::waitpid(pid, nullptr, WNOHANG) == 0; }

// Waits (at most 15 s) until the run has logged `line` (the sink's URL, logged once it serves).
bool wait_for_log(pid_t pid, const fs::path& dir, const std::string& line) {
  for (int i = 0; i < 300 && running(pid); ++i) {
    if (has(slurp(dir / "err"), line)) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

// A run of the static louvre scene (15 cameras, frames:DIR stills) at 30 panoramas/s, 512x512,
// serving `sink` and writing its panoramas to png:DIR/png (`extra`: more options); stopped by stop_run.
pid_t start_run(const fs::path& frames, const std::string& sink, const fs::path& dir,
                const std::string& extra = "") {
  return spawn_omma("run --rig " + (frames / "rig.json").string() + " --source frames:" + frames.string() +
                        " --fps 30 --duration 30 --size 512x512 --no-cache --sink " + sink +
                        " --sink png:" + (dir / "png").string() + " --json " + extra,
                    dir);
}

// SIGTERM (a clean end) and its exit; the seconds it took to exit.
RunResult stop_run(pid_t pid, const fs::path& dir, double* seconds) {
  const auto t0 = Clock::now();
  ::kill(pid, SIGTERM);
  RunResult r = wait_omma(pid, dir);
  *seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return r;
}

nlohmann::json probe(const std::string& input_options, const std::string& url) {
  const RunResult r = run_command(
      "ffprobe -v error " + input_options + " -show_streams -show_format -of json '" + url + "'", 15);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out, nullptr, false);
}

// `frames` decoded frames of the stream (ffmpeg to PNG files in `out`), as read by one reader that
// then disconnects.
std::vector<cv::Mat> read_frames(const std::string& input_options, const std::string& url, int frames,
                                 const fs::path& out) {
  fs::create_directories(out);
  const RunResult r = run_command("ffmpeg -v error " + input_options + " -i '" + url + "' -frames:v " +
                                      std::to_string(frames) + " -y '" + (out / "f%d.png").string() + "'",
                                  15);
  EXPECT_EQ(r.exit_code, 0) << r.err.substr(0, 2000);
  std::vector<cv::Mat> decoded;
  for (int i = 1; i <= frames; ++i) {
    cv::Mat m = cv::imread((out / cv::format("f%d.png", i)).string());
    if (!m.empty()) decoded.push_back(m);
  }
  return decoded;
}

// ffprobe's "N/D" frame rate as a number (0 if it is not one). Neither RTP nor MPEG-TS states a rate:
// ffprobe guesses it from the timestamps, which are the pipeline clock's when each panorama was
// pushed; on a loaded machine it read "59/2" (29.5) once, so the tests allow 3 %.
double frame_rate(const std::string& text) {
  double n = 0, d = 0;
  return std::sscanf(text.c_str(), "%lf/%lf", &n, &d) == 2 && d > 0 ? n / d : 0.0;
}

// The worst PSNR of `frames` against the PNG sink's first panorama (the scene is static).
double worst_psnr(const std::vector<cv::Mat>& frames, const fs::path& png_dir) {
  const cv::Mat ref = cv::imread((png_dir / "frame_000000.png").string());
  EXPECT_FALSE(ref.empty());
  double worst = 1e9;
  for (const auto& f : frames) {
    EXPECT_EQ(f.size(), ref.size());
    if (f.size() == ref.size()) worst = std::min(worst, cv::PSNR(f, ref));
  }
  return frames.empty() || ref.empty() ? 0 : worst;
}

// Checks the run's end: exit 0 within a few seconds of SIGTERM, its summary naming the sink.
void expect_clean_end(pid_t pid, const fs::path& dir, const std::string& url) {
  double seconds = 0;
  const RunResult r = stop_run(pid, dir, &seconds);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LT(seconds, 5.0) << "the run took that long to stop after SIGTERM";
  const auto j = nlohmann::json::parse(r.out, nullptr, false);
  ASSERT_TRUE(j.is_object()) << r.out;
  EXPECT_GT(j.value("frames", 0L), 0L);
  EXPECT_TRUE(has(j["sinks"].dump(), url)) << j["sinks"].dump();
  std::printf("%s: run stopped %.2f s after SIGTERM, %ld panoramas\n", url.c_str(), seconds,
              j.value("frames", 0L));
}

// rtsp://: ffprobe sees H.264 512x512 at 30 frames/s; a reader that takes 2 frames and leaves, then a
// second reader, both get the panorama (PSNR against the PNG sink); the run ends cleanly.
TEST(StreamCli, RtspServesH264ToReadersOneAfterAnother) {
  if (!OMMA_GSTREAMER_BUILT) GTEST_SKIP() << "built without GStreamer";
  if (!have("ffprobe") || !have("ffmpeg")) GTEST_SKIP() << "ffmpeg not installed";
  const fs::path frames = louvre_frames_folder("stream-rtsp-frames");
  const fs::path dir = temp_dir("stream-rtsp");
  const std::string url = "rtsp://127.0.0.1:" + std::to_string(testing::free_port()) + "/pano";
  const pid_t pid = start_run(frames, url, dir);
  ASSERT_GT(pid, 0);
  ASSERT_TRUE(wait_for_log(pid, dir, "RTSP: " + url)) << slurp(dir / "err");
  const std::string tcp = "-rtsp_transport tcp";
  const auto j = probe(tcp, url);
  ASSERT_TRUE(j.is_object() && j.contains("streams") && j["streams"].size() == 1) << j.dump();
  const auto& st = j["streams"][0];
  EXPECT_EQ(st.value("codec_name", ""), "h264");
  EXPECT_EQ(st.value("width", 0), 512);
  EXPECT_EQ(st.value("height", 0), 512);
  EXPECT_EQ(st.value("pix_fmt", ""), "yuv420p");
  EXPECT_NEAR(frame_rate(st.value("r_frame_rate", "")), 30.0, 0.9) << st.value("r_frame_rate", "");
  EXPECT_EQ(read_frames(tcp, url, 2, dir / "first").size(), 2u);  // reads 2 frames and leaves
  // A reader may start on the P-frames sent before its keyframe (ffmpeg shows them as "corrupt
  // decoded frame"): the frames from the 6th on are compared.
  auto second = read_frames(tcp, url, 10, dir / "second");
  ASSERT_EQ(second.size(), 10u);
  second.erase(second.begin(), second.begin() + 5);
  const double psnr = worst_psnr(second, dir / "png");
  std::printf("rtsp: worst PSNR of the second reader's frames against the PNG sink %.1f dB\n", psnr);
  // The bound of SRT's: the same encoder. (With x264's sliced threads ffmpeg's frame-threaded decoder
  // concealed the first slice of every frame over RTP, 15.7 dB: the sinks send one slice per frame.)
  EXPECT_GT(psnr, 35.0);
  EXPECT_TRUE(running(pid)) << "the readers' coming and going stopped the run";
  expect_clean_end(pid, dir, url);
  fs::remove_all(dir);
  fs::remove_all(frames);
}

// srt:// (listener): MPEG-TS with H.264 512x512 at 30 frames/s for ffprobe (ffmpeg's srt protocol
// calls); a reader that leaves and a later one both get the panorama; the run ends cleanly.
TEST(StreamCli, SrtSendsMpegTsToReadersOneAfterAnother) {
  if (!OMMA_GSTREAMER_BUILT) GTEST_SKIP() << "built without GStreamer";
  if (!have("ffprobe") || !have("ffmpeg")) GTEST_SKIP() << "ffmpeg not installed";
  if (run_command("ffmpeg -hide_banner -protocols").out.find("srt") == std::string::npos)
    GTEST_SKIP() << "this ffmpeg has no srt protocol";
  const fs::path frames = louvre_frames_folder("stream-srt-frames");
  const fs::path dir = temp_dir("stream-srt");
  const std::string url = "srt://127.0.0.1:" + std::to_string(testing::free_port());
  const pid_t pid = start_run(frames, url, dir);
  ASSERT_GT(pid, 0);
  ASSERT_TRUE(wait_for_log(pid, dir, "SRT: " + url)) << slurp(dir / "err");
  // MPEG-TS has no header that states the streams: ffprobe reads until it has seen them (at most
  // 1 s of the stream here instead of its default 5 s).
  const std::string quick = "-analyzeduration 1000000";
  const auto j = probe(quick, url);
  ASSERT_TRUE(j.is_object() && j.contains("streams") && j["streams"].size() == 1) << j.dump();
  EXPECT_TRUE(has(j["format"].value("format_name", ""), "mpegts")) << j.dump();
  const auto& st = j["streams"][0];
  EXPECT_EQ(st.value("codec_name", ""), "h264");
  EXPECT_EQ(st.value("width", 0), 512);
  EXPECT_EQ(st.value("height", 0), 512);
  EXPECT_NEAR(frame_rate(st.value("r_frame_rate", "")), 30.0, 0.9) << st.value("r_frame_rate", "");
  EXPECT_EQ(read_frames(quick, url, 2, dir / "first").size(), 2u);
  const auto second = read_frames(quick, url, 5, dir / "second");
  EXPECT_EQ(second.size(), 5u);
  const double psnr = worst_psnr(second, dir / "png");
  std::printf("srt: worst PSNR of the second reader's frames against the PNG sink %.1f dB\n", psnr);
  EXPECT_GT(psnr, 35.0);
  EXPECT_TRUE(running(pid)) << "the readers' coming and going stopped the run";
  expect_clean_end(pid, dir, url);
  fs::remove_all(dir);
  fs::remove_all(frames);
}

// Sends an RTSP request on `fd` and returns the response (headers and body; "" on error or after
// 5 s).
std::string rtsp_request(int fd, const std::string& request) {
  if (::send(fd, request.data(), request.size(), MSG_NOSIGNAL) != ssize_t(request.size())) return "";
  std::string got;
  timeval tv{5, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
  char buf[4096];
  for (;;) {
    const size_t end = got.find("\r\n\r\n");
    if (end != std::string::npos) {
      size_t length = 0;
      if (const size_t at = got.find("Content-Length: "); at != std::string::npos && at < end)
        length = std::stoul(got.substr(at + 16));
      if (got.size() >= end + 4 + length) return got;
    }
    const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
    if (n <= 0) return "";
    got.append(buf, size_t(n));
  }
}

// An RTSP reader that asks for the stream over TCP (RTP interleaved in the RTSP connection), plays
// it and then never reads again (a stuck client: its receive window and the server's backlog for
// it fill up). Returns the connected socket (close it to end the reader) or -1.
int stuck_rtsp_reader(int port, const std::string& url) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  int small = 4096;  // a small receive buffer: the server meets a full window within a frame or two
  ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &small, sizeof(small));
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(uint16_t(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (fd < 0 || ::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) {
    if (fd >= 0) ::close(fd);
    return -1;
  }
  const std::string describe =
      rtsp_request(fd, "DESCRIBE " + url + " RTSP/1.0\r\nCSeq: 1\r\nAccept: application/sdp\r\n\r\n");
  const std::string setup = rtsp_request(fd, "SETUP " + url +
                                                 "/stream=0 RTSP/1.0\r\nCSeq: 2\r\n"
                                                 "Transport: RTP/AVP/TCP;unicast;interleaved=0-1\r\n\r\n");
  const size_t at = setup.find("Session: ");
  EXPECT_TRUE(has(describe, "200 OK") && has(setup, "200 OK") && at != std::string::npos)
      << describe << setup;
  if (at == std::string::npos) {
    ::close(fd);
    return -1;
  }
  const std::string session = setup.substr(at + 9, setup.find_first_of(";\r", at) - at - 9);
  const std::string play = "PLAY " + url + " RTSP/1.0\r\nCSeq: 3\r\nSession: " + session + "\r\n\r\n";
  if (::send(fd, play.data(), play.size(), MSG_NOSIGNAL) != ssize_t(play.size())) {
    ::close(fd);
    return -1;
  }
  return fd;  // and never reads again
}

// rtsp://: a reader that connects, plays over TCP and stops reading neither stops the run nor
// stalls a second, normal reader: ffmpeg gets 60 frames in about their 2 s, and the run keeps its
// 30 panoramas/s.
TEST(StreamCli, RtspStuckReaderDoesNotStallOthers) {
  if (!OMMA_GSTREAMER_BUILT) GTEST_SKIP() << "built without GStreamer";
  if (!have("ffmpeg")) GTEST_SKIP() << "ffmpeg not installed";
  const fs::path frames = louvre_frames_folder("stream-stuck-frames");
  const fs::path dir = temp_dir("stream-stuck");
  const int port = testing::free_port();
  const std::string url = "rtsp://127.0.0.1:" + std::to_string(port) + "/pano";
  const auto t_start = Clock::now();
  // Every panorama a keyframe (--gop 0.02, --crf 10: about 2 MB/s): the server's socket buffer for
  // the stuck reader (650 kB here, `ss`) is full within a second (a static scene's P-frames are a
  // few bytes: they would never fill it).
  const pid_t pid = start_run(frames, url, dir, "--gop 0.02 --crf 10");
  ASSERT_GT(pid, 0);
  ASSERT_TRUE(wait_for_log(pid, dir, "RTSP: " + url)) << slurp(dir / "err");
  const auto t_served = Clock::now();
  const int stuck = stuck_rtsp_reader(port, url);
  ASSERT_GE(stuck, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(2000));  // its window and backlog fill
  // How much the server could not send it: the bytes waiting in its socket (ours, unread).
  int unread = 0;
  ::ioctl(stuck, FIONREAD, &unread);
  const auto t0 = Clock::now();
  auto got = read_frames("-rtsp_transport tcp", url, 60, dir / "normal");
  const double read_s = std::chrono::duration<double>(Clock::now() - t0).count();
  std::printf(
      "rtsp with a stuck reader (%d bytes unread in its socket): a second reader got %zu of 60 frames in "
      "%.2f s\n",
      unread, got.size(), read_s);
  // When the first and the last frame came (the PNG files' times): the reader's start and its rate.
  const auto mtime = [&](int i) {
    std::error_code ec;
    const auto t = fs::last_write_time(dir / "normal" / cv::format("f%d.png", i), ec);
    return ec ? 0.0 : std::chrono::duration<double>(t.time_since_epoch()).count();
  };
  const double first = mtime(1), last = mtime(60);
  std::printf("rtsp with a stuck reader: the second reader's frames 1-60 came in %.2f s (%.1f frames/s)\n",
              last - first, last > first ? 59 / (last - first) : 0.0);
  EXPECT_EQ(got.size(), 60u);
  // 60 frames at 30 frames/s take 2 s (ffmpeg's start included): 1.9-3.8 s here with or without the
  // stuck reader on an idle machine, 3.3-5.2 s when the server waited for the stuck reader
  // (drop-backlog=FALSE, no longer set), and up to 7.1 s with the machine loaded (load 3 on 2
  // cores). The bound catches the second reader held behind the stuck one until its session times
  // out, not those seconds.
  EXPECT_LT(read_s, 10.0) << "the stuck reader stalled the other one";
  if (got.size() > 10) {
    got.erase(got.begin(), got.begin() + 10);
    const double psnr = worst_psnr(got, dir / "png");
    std::printf("rtsp with a stuck reader: the second reader's worst PSNR %.1f dB\n", psnr);
    EXPECT_GT(psnr, 35.0);
  }
  EXPECT_TRUE(running(pid)) << "the stuck reader stopped the run";
  double seconds = 0;
  const RunResult r = stop_run(pid, dir, &seconds);
  const double run_s = std::chrono::duration<double>(Clock::now() - t_served).count() - seconds;
  ::close(stuck);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LT(seconds, 5.0) << "the run took that long to stop after SIGTERM";
  const auto j = nlohmann::json::parse(r.out, nullptr, false);
  ASSERT_TRUE(j.is_object()) << r.out;
  const long panoramas = j.value("frames", 0L);
  // The panoramas of the time it served (it renders a little before it logs the URL).
  const double rate = double(panoramas) / run_s;
  std::printf(
      "rtsp with a stuck reader: %ld panoramas in %.2f s served (%.1f/s; %.2f s since start), stopped "
      "%.2f s after SIGTERM\n",
      panoramas, run_s, rate, std::chrono::duration<double>(t_served - t_start).count(), seconds);
  EXPECT_GT(rate, 25.0) << j.dump();
  fs::remove_all(dir);
  fs::remove_all(frames);
}

// srt:// mode=caller: omma pushes to a listener (ffmpeg, started first) that gets the panorama.
TEST(StreamCli, SrtCallerPushesToAListener) {
  if (!OMMA_GSTREAMER_BUILT) GTEST_SKIP() << "built without GStreamer";
  if (!have("ffmpeg")) GTEST_SKIP() << "ffmpeg not installed";
  if (run_command("ffmpeg -hide_banner -protocols").out.find("srt") == std::string::npos)
    GTEST_SKIP() << "this ffmpeg has no srt protocol";
  const fs::path frames = louvre_frames_folder("stream-srt-caller-frames");
  const fs::path dir = temp_dir("stream-srt-caller");
  fs::create_directories(dir / "listener");
  const int port = testing::free_port();
  const std::string listen = "srt://127.0.0.1:" + std::to_string(port) + "?mode=listener";
  // The listener in the background: 10 frames to PNG, then it exits (MPEG-TS: it reads 1 s of the
  // stream to find the streams, not its default 5 s).
  const pid_t reader = ::fork();
  ASSERT_GE(reader, 0);
  if (reader == 0) {
    const std::string cmd = "exec timeout 20 ffmpeg -v error -analyzeduration 1000000 -i '" + listen +
                            "' -frames:v 10 -y '" + (dir / "listener" / "f%d.png").string() + "' 2>'" +
                            (dir / "listener.err").string() + "'";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // ffmpeg listens
  const std::string url = "srt://127.0.0.1:" + std::to_string(port) + "?mode=caller";
  const auto t0 = Clock::now();
  const pid_t pid = start_run(frames, "'" + url + "'", dir);
  ASSERT_GT(pid, 0);
  int status = 0;
  bool done = false;
  for (int i = 0; i < 300 && !done; ++i) {  // at most 15 s
    done = ::waitpid(reader, &status, WNOHANG) == reader;
    if (!done) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  const double got_s = std::chrono::duration<double>(Clock::now() - t0).count();
  if (!done) {
    ::kill(reader, SIGKILL);
    ::waitpid(reader, &status, 0);
  }
  EXPECT_TRUE(done && WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(dir / "listener.err");
  std::vector<cv::Mat> got;
  for (int i = 1; i <= 10; ++i)
    if (cv::Mat m = cv::imread((dir / "listener" / cv::format("f%d.png", i)).string()); !m.empty())
      got.push_back(m);
  std::printf("srt caller: the listener had %zu of 10 frames %.2f s after the run started\n", got.size(),
              got_s);
  ASSERT_EQ(got.size(), 10u) << slurp(dir / "err");
  got.erase(got.begin(), got.begin() + 5);
  const double psnr = worst_psnr(got, dir / "png");
  std::printf("srt caller: worst PSNR of the listener's frames 6-10 against the PNG sink %.1f dB\n", psnr);
  EXPECT_GT(psnr, 35.0);
  EXPECT_TRUE(running(pid)) << "the listener's leaving stopped the run";
  expect_clean_end(pid, dir, "srt://127.0.0.1:" + std::to_string(port));
  fs::remove_all(dir);
  fs::remove_all(frames);
}

// A socket of ours on 127.0.0.1:port (TCP listening, or UDP bound); -1 if it cannot be made.
int occupy(int port, int type) {
  const int fd = ::socket(AF_INET, type, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(uint16_t(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0 ||
      (type == SOCK_STREAM && ::listen(fd, 1) != 0)) {
    if (fd >= 0) ::close(fd);
    return -1;
  }
  return fd;
}

// Bad specs and a port in use: exit 1 with an error that says what is wrong.
TEST(StreamCli, BadSpecsAndBusyPortsAreClearErrors) {
  const fs::path frames = louvre_frames_folder("stream-bad-frames");
  const std::string run = "run --rig " + (frames / "rig.json").string() +
                          " --source frames:" + frames.string() +
                          " --fps 30 --frames 5 --size 256x256 --no-cache --sink ";
  if (!OMMA_GSTREAMER_BUILT) {
    expect_error(run_omma(run + "rtsp://127.0.0.1:8554/pano", 60), "without GStreamer", "no GStreamer");
    fs::remove_all(frames);
    return;
  }
  const int tcp_port = testing::free_port();
  const int tcp = occupy(tcp_port, SOCK_STREAM);
  ASSERT_GE(tcp, 0);
  expect_error(run_omma(run + "rtsp://127.0.0.1:" + std::to_string(tcp_port) + "/pano", 60),
               "127.0.0.1:" + std::to_string(tcp_port), "rtsp port in use");
  ::close(tcp);
  const int udp_port = testing::free_port();
  const int udp = occupy(udp_port, SOCK_DGRAM);
  ASSERT_GE(udp, 0);
  expect_error(run_omma(run + "srt://127.0.0.1:" + std::to_string(udp_port), 60),
               "127.0.0.1:" + std::to_string(udp_port), "srt port in use");
  ::close(udp);
  expect_error(run_omma(run + "rtsp://127.0.0.1:8554", 60), "path", "rtsp without a path");
  expect_error(run_omma(run + "rtsp://127.0.0.1:8554/", 60), "path", "rtsp with an empty path");
  expect_error(run_omma(run + "rtsp://127.0.0.1:99999/pano", 60), "port", "rtsp port out of range");
  expect_error(run_omma(run + "rtsp://127.0.0.1:http/pano", 60), "port", "rtsp port not a number");
  expect_error(run_omma(run + "rtsp://camera.local:8554/pano", 60), "address", "rtsp host not numeric");
  expect_error(run_omma(run + "'srt://127.0.0.1:9000?mode=rendezvouz'", 60), "mode", "srt bad mode");
  expect_error(run_omma(run + "srt://127.0.0.1", 60), "port", "srt without a port");
  expect_error(run_omma(run + "rtsp://127.0.0.1:8554/pano --codec vp9", 60), "H.264", "vp9 over rtsp");
  fs::remove_all(frames);
}

}  // namespace
}  // namespace omma::test
