// The command line's manners, as a user meets them: examples in every --help that name real options,
// a mistyped command named with the closest one, the build configuration in --version, man pages and
// bash completion generated from the same command tree (apps/help.h, scripts/man.sh).
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core/version.hpp>

#include "tests/cli/cli_util.h"

namespace fs = std::filesystem;
using omma::test::expect_error;
using omma::test::has;
using omma::test::run_command;
using omma::test::run_omma;

namespace {

// The commands listed under "Subcommands:" in a --help text.
std::vector<std::string> listed_subcommands(const std::string& help) {
  std::vector<std::string> subs;
  std::istringstream in(help);
  std::string line;
  bool in_list = false;
  while (std::getline(in, line)) {
    if (line == "Subcommands:") {
      in_list = true;
    } else if (in_list && line.empty()) {
      in_list = false;
    } else if (in_list && line.size() > 2 && line[0] == ' ' && line[1] == ' ' && line[2] != ' ') {
      subs.push_back(line.substr(2, line.find(' ', 2) - 2));
    }
  }
  return subs;
}

// Every command path ("", "rig", "rig check", ...) with its --help text.
std::vector<std::pair<std::string, std::string>> command_tree() {
  std::vector<std::pair<std::string, std::string>> tree;
  std::vector<std::string> todo{""};
  while (!todo.empty()) {
    const std::string path = todo.back();
    todo.pop_back();
    const auto r = run_omma(path + " --help", 30);
    EXPECT_EQ(r.exit_code, 0) << "omma " << path << " --help: " << r.err;
    tree.emplace_back(path, r.out);
    for (const std::string& s : listed_subcommands(r.out)) todo.push_back(path.empty() ? s : path + " " + s);
  }
  return tree;
}

std::string completion(const std::string& words) {
  // COMP_WORDS as bash splits the line; the cursor on the last word ("" after a trailing space).
  const std::string script = std::string(OMMA_BINARY).substr(0, std::string(OMMA_BINARY).rfind('/')) +
                             "/share/bash-completion/completions/omma";
  const auto r =
      run_command("bash -c 'source " + script + " && COMP_WORDS=(" + words +
                      ") && COMP_CWORD=$((${#COMP_WORDS[@]} - 1)) && _omma; echo \"${COMPREPLY[*]}\"'",
                  30);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return r.out.substr(0, r.out.find_last_not_of('\n') + 1);
}

// A man page as `man` shows it, as plain text (col -b removes the overstrike of bold).
omma::test::RunResult rendered(const fs::path& page) {
  return run_command("sh -c 'env LC_ALL=C.UTF-8 MANWIDTH=120 man -l " + page.string() + " | col -b'", 30);
}

}  // namespace

TEST(Manners, ExamplesInEveryHelpUseRealOptions) {
  const auto tree = command_tree();
  ASSERT_GE(tree.size(), 30u);  // 25 commands and their subcommands
  std::map<std::string, std::string> help_of(tree.begin(), tree.end());
  int examples = 0;
  for (const auto& [path, help] : tree) {
    const size_t at = help.find("\nExamples:\n");
    ASSERT_NE(at, std::string::npos) << "no examples in `omma " << path << " --help` (apps/help.cc)";
    std::istringstream in(help.substr(at + 11));
    std::string line;
    int here = 0;
    while (std::getline(in, line) && !line.empty()) {
      // "  omma stitch --rig thesis-24 ... # comment": the command's path, then its options.
      std::string cmd = line.substr(0, line.find('#'));
      cmd = cmd.substr(0, cmd.find("&&"));
      std::istringstream words(cmd);
      std::string w;
      words >> w;
      if (w == "mpirun") {  // mpirun -np 4 omma ...
        while (words >> w && w != "omma") {
        }
      }
      if (w != "omma") continue;  // another tool's line (ffmpeg, nona, source)
      ++here;
      std::string target;
      std::vector<std::string> options;
      bool in_path = true;
      while (words >> w) {
        const std::string longer = target.empty() ? w : target + " " + w;
        if (in_path && w[0] != '-' && help_of.count(longer)) {
          target = longer;
          continue;
        }
        in_path = false;
        if (w.rfind("--", 0) == 0) options.push_back(w.substr(0, w.find('=')));
      }
      for (const std::string& opt : options)
        EXPECT_TRUE(std::regex_search(help_of[target], std::regex("[ ,]" + opt + "[ ,\n]")))
            << "the example `" << line << "` of `omma " << path << "` uses " << opt << ", which `omma "
            << target << "` does not have";
    }
    EXPECT_GE(here, 1) << "`omma " << path << " --help` shows no omma command line";
    examples += here;
  }
  EXPECT_GE(examples, 60);
}

TEST(Manners, UnknownCommandNamedWithClosestMatch) {
  auto r = run_omma("frobnicate", 30);
  expect_error(r, "unknown command 'frobnicate'", "no near command");
  EXPECT_FALSE(has(r.err, "did you mean")) << r.err;
  EXPECT_TRUE(has(r.err, "stitch")) << "the commands are listed: " << r.err;
  r = run_omma("stich --rig thesis-24", 30);
  expect_error(r, "did you mean 'stitch'", "a typo");
  r = run_omma("-v rnder", 30);
  expect_error(r, "did you mean 'render'", "after a flag");
  r = run_omma("hw exprot thesis-24 out", 30);
  expect_error(r, "did you mean 'hw export'", "a subcommand's subcommand");
  r = run_omma("recording chek rec", 30);
  expect_error(r, "did you mean 'recording check'", "one letter missing");
  // Known commands with their positional arguments are left to the command.
  r = run_omma("-q rig check thesis-24", 30);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  // An option's value is not a command, in front of the command or after it.
  r = run_omma("-q stitch --rig thesis-24 --projection rnder --help", 30);
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

TEST(Manners, VersionShowsBuildConfiguration) {
  const auto r = run_omma("--version", 30);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::regex_search(r.out, std::regex("^omma [0-9]+\\.[0-9]+\\.[0-9]+\n"))) << r.out;
  EXPECT_TRUE(has(r.out, std::string("OpenCV: ") + CV_VERSION + "\n")) << r.out;
  for (const char* key : {"MPI (mpirun omma render): ", "RTL co-simulation (hw/rtl): ", "Python bindings: "})
    EXPECT_TRUE(std::regex_search(
        r.out,
        std::regex(std::string("\n") + std::regex_replace(key, std::regex("[()/]"), "\\$&") + "(yes|no)\n")))
        << key << " in " << r.out;
  // The kernel it reports is the one `omma bench` and the renderer pick (render.h best_kernel).
  EXPECT_TRUE(std::regex_search(r.out, std::regex("render kernel: (scalar|avx2|avx512-vnni) \\(of scalar")))
      << r.out;
  // The Python module beside the binary means the bindings were built.
  const fs::path build = fs::path(OMMA_BINARY).parent_path();
  EXPECT_EQ(has(r.out, "Python bindings: yes"), fs::exists(build / "python" / "omma")) << r.out;
}

TEST(Manners, BashCompletionFromTheCommandTree) {
  EXPECT_EQ(completion("omma sti"), "stitch");
  EXPECT_EQ(completion("omma hw ex"), "export");
  EXPECT_EQ(completion("omma stitch --met"), "--method");
  EXPECT_EQ(completion("omma design --method \"\""), "layered min-cameras max-volume cvt");
  EXPECT_EQ(completion("omma isp --awb \"\""), "none grayworld whitepatch");
  EXPECT_EQ(completion("omma -v recording \"\""), "check --help");
  // After an option that takes a value, file names; after a flag, the command's words again.
  const fs::path dir = omma::test::temp_dir("completion");
  std::ofstream(dir / "my_rig.json") << "{}";
  EXPECT_EQ(completion("omma stitch --rig " + (dir / "my_").string()), (dir / "my_rig.json").string());
  EXPECT_TRUE(has(completion("omma stitch --json --fr"), "--frames"));
  // The installed script is what `omma completion bash` prints now.
  const auto r = run_omma("completion bash", 30);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, omma::test::slurp(fs::path(OMMA_BINARY).parent_path() /
                                     "share/bash-completion/completions/omma"));
  fs::remove_all(dir);
}

TEST(Manners, ManPagesForEveryCommand) {
  const fs::path man = fs::path(OMMA_BINARY).parent_path() / "man" / "man1";
  if (run_command("sh -c 'command -v help2man'", 10).exit_code != 0) GTEST_SKIP() << "help2man not installed";
  const auto top = run_omma("--help", 30);
  std::vector<std::string> pages{"omma"};
  for (const std::string& s : listed_subcommands(top.out)) pages.push_back("omma-" + s);
  ASSERT_GE(pages.size(), 20u);
  for (const std::string& page : pages) {
    const fs::path file = man / (page + ".1");
    ASSERT_TRUE(fs::exists(file)) << file;
    // man renders it (groff), with the sections a reader looks for.
    const auto r = rendered(file);
    EXPECT_EQ(r.exit_code, 0) << r.out;
    for (const char* section : {"NAME", "SYNOPSIS", "DESCRIPTION", "EXAMPLES"})
      EXPECT_TRUE(std::regex_search(r.out, std::regex(std::string("\n") + section + "\n")))
          << page << ": " << section << " in:\n"
          << r.out;
    const std::string command = page == "omma" ? "omma" : "omma " + page.substr(5);
    EXPECT_TRUE(has(r.out, command)) << page;
  }
  const auto r = rendered(man / "omma-stitch.1");
  EXPECT_TRUE(has(r.out, "omma stitch --rig thesis-24 --frames frames --out pano.png")) << r.out;
  EXPECT_TRUE(has(r.out, "--method")) << r.out;
}
