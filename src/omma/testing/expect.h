// Helpers for the tests' expectations.
#pragma once

#include <stdexcept>
#include <string>

namespace omma::testing {

// The message of the std::invalid_argument that f() throws, or "" if it throws none: a test that
// options are refused checks that the message names the bad option.
template <typename F>
std::string refusal(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace omma::testing
