// omma conventions: the one source of truth. Every other file refers here.
//
// Frames and angles (thesis eq. 5.15)
//   * Dome frame: right-handed, origin at the dome centre, dome axis (the "pole") is +z.
//   * A direction is a unit vector w. Spherical angles: theta = polar angle from +z (0 at the pole,
//     90 deg at the dome rim), phi = azimuth from +x towards +y.
//       w = sin(theta) cos(phi) x + sin(theta) sin(phi) y + cos(theta) z          (eq. 5.15)
//   * Camera frame (eq. 2.4, Fig. 2.4b): three orthonormal vectors in dome coordinates,
//       t = optical axis (viewing direction, out of the dome),
//       u = image +x axis (columns grow along u),
//       v = image +y axis (rows grow along v, i.e. "down" in the picture),
//     right-handed: t x u = v, u x v = t, v x t = u.
//   * Yaw (alpha), pitch (beta), roll (gamma) (eq. 3.13): Rt = Rx(gamma) Ry(beta) Rz(alpha) and
//     [t; u; v] = Rt [x; y; z], i.e. t, u, v are the ROWS of Rt. All zero gives t=+x, u=+y, v=+z.
//
// Units
//   * Files (rig JSON, PTO, CSV, reports, command-line options): millimetres and degrees.
//   * Inside the library: millimetres and RADIANS. Convert at the boundary with deg2rad/rad2deg.
//
// Pixels
//   * Pixel (col, row) covers the square [col, col+1) x [row, row+1); its centre is at
//     (col + 0.5, row + 0.5). Continuous image coordinates use this convention everywhere
//     (principal point cu, cv included: a centred principal point of a W x H image is W/2, H/2).
//   * OpenCV samplers (cv::remap) put centres at integers: subtract 0.5 when calling them.
//
// Camera model (eq. 5.21-5.26, applied to normalised coordinates so that k1..k5 are unitless)
//   x = (w.u)/(w.t), y = (w.v)/(w.t), R2 = x^2 + y^2, p = 1 + k1 R2 + k2 R2^2 + k5 R2^3,
//   x' = p x + 2 k4 x y + k3 (R2 + 2 x^2),  y' = p y + 2 k3 x y + k4 (R2 + 2 y^2),
//   col = cu + fu x',  row = cv + fv y'.
//   A camera sees w when w.t >= cos(aov/2) (eq. 2.3); aov is the full (diagonal-free, circular)
//   angle of view of the camera cone, in (0, 180) degrees.
//
// Panorama grids (see grid.h)
//   * equirect: 360 x 90 degrees, dome axis (theta = 0) along the top row, theta grows downwards to
//     90 deg at the bottom row, phi grows left to right from 0 to 360 deg.
//   * vr180: 180 x 180 degrees half-equirectangular, dome axis at the image centre, image right = +x,
//     image up = +y.
//   * equirect360x180 (full sphere rigs): theta 0..180 deg top to bottom.
#pragma once

namespace omma {

inline constexpr double kPi = 3.14159265358979323846;
constexpr double deg2rad(double deg) { return deg * kPi / 180.0; }
constexpr double rad2deg(double rad) { return rad * 180.0 / kPi; }

}  // namespace omma
