// omma's version: one source, the file VERSION at the top of the source tree, which CMake reads into
// project(VERSION) and compiles into version.cc. `omma --version`, the Python package's __version__
// and pip's metadata (pyproject.toml) all come from it. Semantic versioning: before 1.0 a minor
// version may break files and interfaces (CHANGELOG.md says how).
#pragma once

#include <string>

namespace omma {

// "MAJOR.MINOR.PATCH", e.g. "0.2.0".
std::string version();

}  // namespace omma
