// The refusal every options struct's IsValid(std::string* why) gives (CONTRIBUTING.md, "IsValid on
// options"): the reason into *why when the caller asked for it, and false.
#pragma once

#include <string>

namespace omma {

inline bool invalid(std::string* why, const std::string& reason) {
  if (why) *why = reason;
  return false;
}

// "" if options.IsValid(), else its reason: for checking several option structs in one place.
template <class Options>
std::string valid_or_why(const Options& options) {
  std::string why;
  return options.IsValid(&why) ? std::string() : why;
}

}  // namespace omma
