// CLI tests of `omma run`'s live view over HTTP, read back with curl: /stats.json while the run goes
// (render time, not only at the end), the address (--bind) and the token (--token) that guards
// every resource but the viewer's own files. Only loopback addresses (127.0.0.0/8) are bound here.
#include <sys/wait.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "omma/core/rig.h"
#include "omma/testing/net.h"
#include "omma/testing/synthetic.h"
#include "tests/cli/cli_util.h"

namespace omma::test {
namespace {
namespace fs = std::filesystem;
using std::chrono::milliseconds;

fs::path write_rig(const fs::path& dir) {
  const fs::path p = dir / "rig.json";
  save_rig(testing::test_rig_24(64, 64), p);
  return p;
}

std::string lake() { return data_dir() + "/lake.jpg"; }

// Stops `omma` (SIGTERM: a clean end) and collects its exit status and output.
RunResult stop_omma(pid_t pid, const fs::path& dir) {
  ::kill(pid, SIGTERM);
  return wait_omma(pid, dir);
}

bool running(pid_t pid) { return ::waitpid(pid, nullptr, WNOHANG) == 0; }

// curl's answer: "STATUS BODY" (STATUS 000: no connection).
struct Answer {
  int status = 0;
  std::string body;
};
Answer curl(const std::string& url) {
  const RunResult r = run_command("curl -s --max-time 5 -w '\\n%{http_code}' '" + url + "'", 10);
  Answer a;
  const size_t nl = r.out.rfind('\n');
  if (nl == std::string::npos) return a;
  a.status = std::atoi(r.out.c_str() + nl + 1);
  a.body = r.out.substr(0, nl);
  return a;
}

// /stats.json once the engine has published its first statistics (at most 20 s).
nlohmann::json live_stats(const std::string& base, const std::string& query, pid_t pid) {
  for (int i = 0; i < 200 && running(pid); ++i) {
    const Answer a = curl(base + "stats.json" + query);
    if (a.status == 200) {
      const auto j = nlohmann::json::parse(a.body, nullptr, false);
      if (j.is_object() && j.contains("frames") && j["frames"].get<long>() > 0) return j;
    }
    std::this_thread::sleep_for(milliseconds(100));
  }
  return nullptr;
}

// /stats.json reports the render time while the run goes (it used to say 0 until the end): the
// running mean and the last interval's, both positive, read with curl from a run still rendering.
TEST(LiveCli, StatsReportRenderTimeWhileRunning) {
  if (std::system("command -v curl >/dev/null 2>&1") != 0) GTEST_SKIP() << "curl missing";
  const auto dir = temp_dir("live-stats");
  const int port = testing::free_port();
  const pid_t pid = spawn_omma(
      "run --rig " + write_rig(dir).string() + " --source pano:" + lake() +
          "@20 --size 128x128 --no-cache --duration 60 --sink http:" + std::to_string(port) + " --json",
      dir);
  ASSERT_GT(pid, 0);
  const std::string base = "http://127.0.0.1:" + std::to_string(port) + "/";
  const nlohmann::json first = live_stats(base, "", pid);
  std::this_thread::sleep_for(milliseconds(700));  // another interval
  const nlohmann::json second = live_stats(base, "", pid);
  const bool still_running = running(pid);
  const RunResult r = stop_omma(pid, dir);
  ASSERT_TRUE(first.is_object()) << r.err;
  ASSERT_TRUE(second.is_object()) << r.err;
  EXPECT_TRUE(still_running);
  std::printf("  live: %ld frames, render %.3f ms (last interval %.3f ms); later %ld frames, %.3f ms\n",
              first["frames"].get<long>(), first["render_ms_mean"].get<double>(),
              first["window"]["render_ms"].get<double>(), second["frames"].get<long>(),
              second["render_ms_mean"].get<double>());
  for (const auto& j : {first, second}) {
    EXPECT_GT(j["render_ms_mean"].get<double>(), 0.0) << j.dump();
    EXPECT_LT(j["render_ms_mean"].get<double>(), 1000.0) << j.dump();
    EXPECT_GT(j["window"]["render_ms"].get<double>(), 0.0) << j.dump();
  }
  EXPECT_GT(second["frames"].get<long>(), first["frames"].get<long>());
  // The run's own summary agrees in kind.
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GT(r.json()["render_ms_mean"].get<double>(), 0.0);
  fs::remove_all(dir);
}

// --token random on loopback: the URL with its token is printed; every resource but the viewer's
// files answers 403 without it or with a wrong one (of the same length), 200 with it. No network
// warning on loopback; 127.0.0.2 counts as loopback (no token by default). Bad --bind and --token
// values are refused before anything starts.
TEST(LiveCli, TokenGuardsEverythingButTheViewerFiles) {
  if (std::system("command -v curl >/dev/null 2>&1") != 0) GTEST_SKIP() << "curl missing";
  const auto dir = temp_dir("live-token");
  const auto rig = write_rig(dir);
  const std::string run = "run --rig " + rig.string() + " --source pano:" + lake() +
                          "@20 --size 96x96 --no-cache --duration 60 --json ";
  int port = testing::free_port();
  pid_t pid =
      spawn_omma(run + "--sink http:" + std::to_string(port) + " --bind 127.0.0.1 --token random", dir);
  ASSERT_GT(pid, 0);
  const std::string base = "http://127.0.0.1:" + std::to_string(port) + "/";
  std::string token;
  for (int i = 0; i < 200 && token.empty() && running(pid); ++i) {
    std::this_thread::sleep_for(milliseconds(100));
    const std::string err = slurp(dir / "err");
    if (const size_t at = err.find(base + "?token="); at != std::string::npos)
      token = err.substr(at + base.size() + 7, 32);
  }
  const nlohmann::json stats = live_stats(base, "?token=" + token, pid);
  std::map<std::string, int> without, wrong, with;
  std::string wrong_token = token;
  if (!wrong_token.empty()) wrong_token.back() = wrong_token.back() == '0' ? '1' : '0';
  for (const char* path : {"", "stats.json", "config.json", "frame.jpg", "stream.mjpg", "no-such-file",
                           "viewer/pannellum.js", "viewer/live.js"}) {
    without[path] = curl(base + path).status;
    wrong[path] = curl(base + path + "?token=" + wrong_token).status;
    // (the stream runs until curl's time limit: its status line is what counts)
    with[path] = std::string(path) == "stream.mjpg"
                     ? std::atoi(run_command("curl -s -o /dev/null --max-time 1 -w '%{http_code}' '" + base +
                                                 path + "?token=" + token + "'",
                                             10)
                                     .out.c_str())
                     : curl(base + path + "?token=" + token).status;
  }
  const Answer page = curl(base + "?token=" + token);
  RunResult r = stop_omma(pid, dir);
  ASSERT_EQ(token.size(), 32u) << r.err;
  EXPECT_EQ(token.find_first_not_of("0123456789abcdef"), std::string::npos) << token;
  EXPECT_TRUE(stats.is_object()) << r.err;
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(has(r.err, "visible to the network")) << r.err;
  for (const char* path : {"", "stats.json", "config.json", "frame.jpg", "stream.mjpg", "no-such-file"}) {
    EXPECT_EQ(without[path], 403) << path;
    EXPECT_EQ(wrong[path], 403) << path;
  }
  for (const char* path : {"", "stats.json", "config.json", "frame.jpg", "stream.mjpg"})
    EXPECT_EQ(with[path], 200) << path;
  EXPECT_EQ(with["no-such-file"], 404);
  for (const char* path : {"viewer/pannellum.js", "viewer/live.js"}) {
    EXPECT_EQ(without[path], 200) << path;
    EXPECT_EQ(with[path], 200) << path;
  }
  EXPECT_TRUE(has(page.body, "live.js")) << page.body;
  // The summary names the address, never the token.
  EXPECT_FALSE(has(r.out, token)) << r.out;

  // 127.0.0.2 is loopback: no token by default, no warning.
  port = testing::free_port();
  pid = spawn_omma(run + "--sink http:" + std::to_string(port) + " --bind 127.0.0.2", dir);
  const std::string base2 = "http://127.0.0.2:" + std::to_string(port) + "/";
  const nlohmann::json stats2 = live_stats(base2, "", pid);
  r = stop_omma(pid, dir);
  EXPECT_TRUE(stats2.is_object()) << r.err;
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(has(r.err, "live view: " + base2)) << r.err;
  EXPECT_FALSE(has(r.err, "token=")) << r.err;
  EXPECT_FALSE(has(r.err, "visible to the network")) << r.err;

  // Bad values: clear errors, exit 1.
  expect_error(run_omma(run + "--sink http:" + std::to_string(port) + " --bind my.host", 30), "my.host",
               "--bind not an address");
  expect_error(run_omma(run + "--sink http:" + std::to_string(port) + " --token maybe", 30), "--token",
               "--token unknown");
  expect_error(run_omma(run + "--sink http://127.0.0.3:" + std::to_string(port) + " --bind 127.0.0.2", 30),
               "--bind", "two addresses");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace omma::test
