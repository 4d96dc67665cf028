// Scenes for the dome simulator: what a ray from the dome sees.
//
// Frames and units (conventions.h): a scene lives in its own "scene frame", in millimetres. With the
// dome at rest (DomePose identity, render.h) the scene frame IS the dome frame: dome centre at the
// origin, dome axis +z. Directions are unit vectors.
//
// Radiance is LINEAR light (not gamma-encoded), BGR order like OpenCV images, nominally in [0, 1]
// (1 = the sensor's full scale at exposure 1; values may exceed 1 and then clip in the camera).
// The simulator encodes frames and the ground truth with the sRGB curve (render.h), so a photo scene
// rendered by an ideal camera reproduces the photo's own pixel values.
#pragma once

#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

#include "omma/core/geometry.h"
#include "omma/core/srgb.h"

namespace omma::sim {

class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Scene {
 public:
  virtual ~Scene() = default;
  // Linear BGR radiance seen along the ray origin + s * dir (s > 0). origin and light in mm, scene
  // frame; dir a unit vector. `light` is where the dome's light source is (the dome centre); scenes
  // lit by the dome (colon) use it, far-field and self-lit scenes ignore it.
  virtual cv::Vec3f radiance(const Vec3& origin, const Vec3& dir, const Vec3& light) const = 0;
  // Distance (mm) along the ray origin + s * dir (dir a unit vector) to the surface point whose
  // radiance radiance() returns; +infinity for far-field scenes and for rays that meet nothing
  // within the scene's range (the colon's dark lumen beyond 400 mm). The ground-truth depth
  // (render_truth_depth).
  virtual double distance(const Vec3& origin, const Vec3& dir) const {
    (void)origin;
    (void)dir;
    return std::numeric_limits<double>::infinity();
  }
  // The spec this scene was made from (e.g. "colon", "photo:/path/louvre.jpg").
  virtual std::string spec() const = 0;
  // How an animated rig moves through this scene (the live sim: source, live/sim_loop.h): back and
  // forth along `direction` (unit vector, scene frame) at the default peak speed `speed_mm_s`;
  // nullopt (the default): the scene says nothing (the colon travels along z, others turn).
  struct Travel {
    Vec3 direction = Vec3::UnitZ();
    double speed_mm_s = 5;
  };
  virtual std::optional<Travel> travel() const { return std::nullopt; }
};

// Far-field equirectangular 360 x 180 deg photograph (any size, 8- or 16-bit, 1 or 3 channels):
// only the ray's direction matters. The photo is read as an omma equirect-full panorama, the way
// every 360-degree viewer shows it (conventions.h (G1)): photo column x <-> azimuth
// phi = -2 pi x / W (mod 2 pi), photo row y <-> polar angle theta = pi y / H, so the photo's top
// row is the dome axis +z (zenith), its centre row the horizon, and a camera of the rig sees the
// photo the right way round (text reads correctly in the simulated frames). Bilinear sampling in
// linear light, wrapping in x. Throws SceneError if the file is missing or unreadable.
std::unique_ptr<Scene> make_photo_scene(const std::string& path);
// The same from an image in memory (BGR or gray, 8U/16U/32F; 32F taken as sRGB-encoded in [0, 1]).
std::unique_ptr<Scene> make_photo_scene(const cv::Mat& equirect, const std::string& spec = "photo:memory");

// Procedural colon: a tube along the scene z axis (periodic in z, period 240 mm, so an animated dome
// can travel any distance), mean diameter about 42 mm varying between about 36 and 48 mm, with
// haustral folds every 24 mm (semilunar ridges up to 5 mm high), a reddish mucosa with a vascular
// texture, and four polyps (4.5-6 mm high, at z = 12, 24, 33, 58 mm). Lit by a point source at `light`
// (Lambert, inverse-square), so brightness falls with distance. Ray-surface intersection marches a
// precomputed radius table R(z, phi) (0.15 mm cells) with Lipschitz-safe steps, then bisects.
// Rays travelling more than 400 mm, or starting outside the tube, see black.
struct ColonParams {
  double radius_mm = 21.0;        // mean tube radius
  double light_distance_mm = 16;  // a white wall facing the light at this distance has radiance = albedo
  double light_power = 1.0;       // overall illumination scale
  unsigned seed = 7;              // texture seed
};
std::unique_ptr<Scene> make_colon_scene(const ColonParams& params = {});

// Bounds of the scene parameters (every make_*_scene refuses values outside them): distances and
// radii up to 1 km (the dome is 5 mm; farther is the far field), radiance levels up to 1000 x the
// sensor's full scale (beyond that every pixel clips anyway).
inline constexpr double kMaxSceneMm = 1e6;
inline constexpr double kMaxSceneLevel = 1e3;

// USAF 1951 chart on the plane z = distance_mm (default 25 mm, thesis §5.5.2), black bars on a white
// card, uniformly lit (usaf.h gives the chart geometry). Outside the card: mid grey; rays that never
// reach the plane (dir.z <= 0): dark.
std::unique_ptr<Scene> make_usaf_scene(double distance_mm = 25.0);

// A sphere of radius radius_mm centred on the scene origin, textured with a coloured 10 deg
// checkerboard in (theta, phi) plus fine 2 deg lines, seen from inside (parallax grows as the
// radius shrinks). Throws SceneError if radius_mm <= 0 or the origin of a ray is outside it.
std::unique_ptr<Scene> make_checker_scene(double radius_mm = 100.0);

// The thesis's calibration environment (§3.6, Fig. 3.12a): a closed cylindrical tube of
// `diameter_mm` (35 mm in the thesis, "compatible with the human bowel") on the dome axis, the dome
// centre on its axis, its far end closed by a disc `length_mm` ahead (+z) and its back `back_mm`
// behind; evenly lit (radiance = brightness * albedo, no shading: a static, well-lit target). The
// print is a high-contrast pattern with detail at every scale the cameras resolve (octaves of
// value noise from 12.8 mm down to 0.1 mm cells, equal amplitude, through a steep sigmoid: albedo
// 0.06 .. 0.94) tinted by a coarse colour noise (every channel textured). Static: shots of it
// differ only by the sensor noise.
struct TubeParams {
  double diameter_mm = 35;
  double length_mm = 30;     // far end (closed) ahead of the dome centre
  double back_mm = 60;       // closed end behind the dome centre
  double brightness = 0.85;  // radiance of a white print
  unsigned seed = 11;        // texture seed
};
std::unique_ptr<Scene> make_tube_scene(const TubeParams& params = {});

// A uniformly lit white target (an integrating sphere): the same radiance `level` in every
// direction, for flat-field photometric calibration (calib/photometric.h).
std::unique_ptr<Scene> make_flat_scene(double level = 0.6);

// Parses a scene spec: "photo:PATH", "colon", "usaf[:DIST_MM]", "checker[:RADIUS_MM]",
// "tube[:DIAMETER_MM]", "flat[:LEVEL]", "room" (the built-in room: a corridor around the rig with
// objects from 0.5 to 10 m, sim/room.h), "room:PATH" (a room file, format in sim/room.h). Throws
// SceneError with the list of valid specs for anything else, or if the photo cannot be read.
std::unique_ptr<Scene> make_scene(const std::string& spec);

// sRGB transfer curve (IEC 61966-2-1), values in [0, 1]: core/srgb.h.
using ::omma::linear_to_srgb;
using ::omma::srgb_to_linear;

}  // namespace omma::sim
