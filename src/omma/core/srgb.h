// The sRGB transfer curve (IEC 61966-2-1): the encoding of every 8-bit frame, panorama and photo
// in omma (the simulator writes sRGB, the ISP can output it, the photometric model is applied in
// the linear light between decode and encode). Values in [0, 1], clamped (NaN
// counts as 0).
#pragma once

#include <algorithm>
#include <cmath>

namespace omma {

inline float srgb_to_linear(float e) {
  e = e > 0 ? std::min(e, 1.0f) : 0.0f;  // (std::clamp would pass NaN through)
  return e <= 0.04045f ? e / 12.92f : std::pow((e + 0.055f) / 1.055f, 2.4f);
}

inline float linear_to_srgb(float l) {
  l = l > 0 ? std::min(l, 1.0f) : 0.0f;
  return l <= 0.0031308f ? 12.92f * l : 1.055f * std::pow(l, 1.0f / 2.4f) - 0.055f;
}

}  // namespace omma
