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
// Panorama grids (grid.h derives every projection from the two equations below, in one place)
//   A panorama shows the world as a person standing at the rig's centre sees it: never mirrored.
//   Looking along a direction f with "up" h, the viewer's right is r = f x h (right-handed frame).
//   * Longitude-latitude grids (equirect, equirect-full, equirect-100): up = the dome axis +z, so a
//     viewer facing azimuth phi has phi - 90 deg on the right: TURNING RIGHT DECREASES PHI, and the
//     image right is the viewer's right (as in Hugin/PanoTools, PTGui and every 360-degree viewer):
//       phi(x) = -2 pi x / W  (mod 2 pi),   theta(y) = span_v * y / H                       (G1)
//     with x, y continuous pixel coordinates. The left edge of column 0 looks at phi = 0 (+x), the
//     image centre at phi = 180 deg (-x); the top row at theta = 0 (the dome axis).
//       equirect       360 x 90 deg  (span_v =  90 deg, dome rigs: the dome axis is the zenith)
//       equirect-full  360 x 180 deg (span_v = 180 deg, full-sphere rigs and far-field photos)
//       equirect-100   360 x 100 deg (span_v = 100 deg, Giga-Eye, thesis Table 7.4)
//     PanoTools' equirect longitude lambda (0 at its image centre, growing to the right) is
//     lambda = 180 deg - phi, so its pixels are omma's equirect-full pixels (calib/pto.h).
//   * vr180: 180 x 180 deg half-equirectangular, looking along the dome axis +z with image up = +y,
//     so the image right is r = z x y = -x:
//       lon(x) = 90 deg - 180 deg * x / W  (the angle about +y from +z towards +x),
//       lat(y) = 90 deg - 180 deg * y / H  (towards +y),
//       w = (cos(lat) sin(lon), sin(lat), cos(lat) cos(lon))                               (G2)
//     The image centre looks along +z, image right along -x, image up along +y.
//   A camera frame with u x v = t (above) is itself unmirrored, so a camera's picture and the panorama
//   show the same scene the same way round (tested with SIFT, Hugin's nona and OCR in grid_test.cc,
//   pto_test.cc and handedness_test.cc).
#pragma once

namespace omma {

inline constexpr double kPi = 3.14159265358979323846;

// Version of the panorama grid convention above, part of every cache key that depends on it (map
// files, render/compiled_map.h): 1 = the mirrored grids of omma 0.1 (phi grew to the right, vr180's
// right was +x); 2 = (G1)/(G2), the world the right way round.
inline constexpr int kGridConvention = 2;
constexpr double deg2rad(double deg) { return deg * kPi / 180.0; }
constexpr double rad2deg(double rad) { return rad * 180.0 / kPi; }

}  // namespace omma
