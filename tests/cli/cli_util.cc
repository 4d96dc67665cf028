#include "tests/cli/cli_util.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "omma/testing/test_scenes.h"

namespace omma::test {
namespace fs = std::filesystem;

nlohmann::json RunResult::json() const { return nlohmann::json::parse(out); }

RunResult run_omma(const std::string& args, int timeout_s) {
  return run_command(OMMA_BINARY " " + args, timeout_s);
}

RunResult run_command(const std::string& command, int timeout_s) {
  const fs::path dir = temp_dir("run");
  const std::string cmd = "timeout " + std::to_string(timeout_s) + " " + command + " >" +
                          (dir / "out").string() + " 2>" + (dir / "err").string() + " </dev/null";
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = slurp(dir / "out");
  r.err = slurp(dir / "err");
  fs::remove_all(dir);
  return r;
}

pid_t spawn_omma(const std::string& args, const fs::path& dir, const std::string& prefix) {
  const std::string cmd = "exec " + prefix + " " OMMA_BINARY " " + args + " >" + (dir / "out").string() +
                          " 2>" + (dir / "err").string() + " </dev/null";
  const char* argv[] = {"/bin/sh", "-c", cmd.c_str(), nullptr};
  pid_t pid = -1;
  if (posix_spawn(&pid, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ) != 0) return -1;
  return pid;
}

RunResult wait_omma(pid_t pid, const fs::path& dir) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = slurp(dir / "out");
  r.err = slurp(dir / "err");
  return r;
}

fs::path temp_dir(const std::string& tag) {
  std::random_device rd;
  const fs::path p = fs::temp_directory_path() / ("omma-test-" + tag + "-" + std::to_string(rd()));
  fs::create_directories(p);
  return p;
}

std::string data_dir() { return OMMA_DATA_DIR; }

fs::path louvre_frames_folder(const std::string& tag) {
  const fs::path dir = temp_dir(tag);
  const Rig rig = testing::small_rig(64);
  const cv::Mat tex = testing::photo_texture(data_dir() + "/louvre.jpg", 360);
  const PanoGrid grid{Projection::kVr180, 128, 128};
  testing::write_frames_folder(dir, rig, testing::render_frames(rig, tex), testing::render_truth(grid, tex));
  return dir;
}

double eval_psnr(const std::filesystem::path& pano, const std::filesystem::path& truth) {
  const RunResult e = run_omma("eval --pano " + pano.string() + " --truth " + truth.string() + " --json");
  EXPECT_EQ(e.exit_code, 0) << e.err;
  return e.exit_code == 0 ? e.json().at("psnr_db").get<double>() : 0.0;
}

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

int count(const std::string& s, const std::string& what) {
  int n = 0;
  for (size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
  return n;
}

bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

void expect_error(const RunResult& r, const std::string& part, const std::string& what) {
  EXPECT_EQ(r.exit_code, 1) << what << "\n" << r.err;
  EXPECT_TRUE(has(r.err, "omma: error:")) << what << "\n" << r.err;
  EXPECT_TRUE(has(r.err, part)) << what << ": no '" << part << "' in\n" << r.err;
}

}  // namespace omma::test
