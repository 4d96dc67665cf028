// Numbers read from text and from JSON, the same way wherever they enter: whole or not at all, and
// compared with their bounds before they are narrowed. The caller words the error and adds its own
// bounds (finiteness included).
#pragma once

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace omma {

// `text` as a number if the WHOLE of it is one, in std::stod's syntax (leading blanks, decimal or
// hexadecimal floating point, inf, nan); nullopt for anything else: empty text, trailing characters
// (an embedded NUL included), and a value beyond double's range, which std::stod refuses too.
inline std::optional<double> parse_double(const std::string& text) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || end != text.c_str() + text.size() || errno == ERANGE) return std::nullopt;
  return v;
}

// `v` as a 64-bit integer if it is a JSON integer (not a float or a boolean; nlohmann holds integers
// beyond 64 bits as floats) within [lo, hi], compared before narrowing so that nothing wraps;
// nullopt otherwise.
inline std::optional<std::int64_t> json_integer(const nlohmann::json& v, std::int64_t lo, std::int64_t hi) {
  if (!v.is_number_integer()) return std::nullopt;
  if (v.is_number_unsigned()) {
    const std::uint64_t u = v.get<std::uint64_t>();
    if (u > std::uint64_t(std::max<std::int64_t>(hi, 0)) || std::int64_t(u) < lo) return std::nullopt;
    return std::int64_t(u);
  }
  const std::int64_t s = v.get<std::int64_t>();
  if (s < lo || s > hi) return std::nullopt;
  return s;
}

}  // namespace omma
