// The command line's manners, beside the table of subcommands (main.cc): examples in every --help,
// the closest command named for a mistyped one, the build configuration in --version, and bash
// completion generated from the same tree of commands and options that parses the arguments.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace omma::app {

// Adds an "Examples:" footer to the --help of `root` and of every subcommand under it, from one
// table (help.cc) keyed by the command's path ("stitch", "hw export"). A command missing from the
// table gets none, and the test Manners.ExamplesInEveryHelp fails naming it.
void add_examples(CLI::App& root);

// The path of `app` below the root: "hw export"; "" for the root.
std::string command_path(const CLI::App& app);

// The candidate closest to `word` by edit distance (Damerau-Levenshtein with adjacent
// transpositions, case-insensitive), or "" when none is within max(2, size / 3) edits.
std::string closest_match(const std::string& word, const std::vector<std::string>& candidates);

// Before parsing: an argument where `app` expects a subcommand that is none of its subcommands
// gives "unknown command 'X' (did you mean 'Y'?)". Returns the error text, "" when the command
// line names only known commands (options and their values are left to CLI11).
std::string unknown_command_error(const CLI::App& root, const std::vector<std::string>& args);

// "omma 0.2.0" and the build configuration: build type, compiler, OpenCV, MPI, RTL, Python, the
// render kernel this CPU runs, one "key: value" per line.
std::string version_text();

// A bash completion script for `root` (subcommands, options, choices of options with a fixed set),
// for `source` or /usr/share/bash-completion/completions/omma.
std::string bash_completion(const CLI::App& root);

// `omma completion bash`: prints bash_completion() of the root.
void add_completion_command(CLI::App& root);

}  // namespace omma::app
