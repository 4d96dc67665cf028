// A room around the rig, described by a JSON file: the near scene at Giga-Eye's scale (objects from
// about 0.5 m to 10 m, true depth per ray), made of analytic primitives.
//
// Scene specs (scene.h make_scene):
//   room          the built-in room, data/scenes/room.json embedded in the binary at build time (a
//                 corridor 12.5 x 5 x 3 m, 37 objects from 0.49 m to 9.5 m; data/scenes/README.md)
//   room:PATH     a room file of one's own (PATH relative to the working directory)
//
// Frame and units: millimetres, the scene frame (= the rig frame at rest, scene.h): rig centre at the
// origin, +z up = Giga-Eye's zenith camera axis. Giga-Eye sees polar angles 0 .. about 105 deg, so
// the ceiling, the walls and the horizon fill its view and the floor is seen only at the edges.
//
// Radiance (linear BGR, scene.h) is self-lit and view-independent (Lambert under a fixed light, so
// every camera sees the same value at a surface point, as depth matching assumes):
//   L = colour * (1 + contrast * tanh(1.5 n)) * tint * (ambient + (1 - ambient) max(0, N.l))   (R1)
// N = the surface normal facing the ray's origin, l = the unit light direction; n = the material's
// fractal value noise at the surface point, normalised to unit standard deviation: octaves of cells
// largest_mm, largest_mm / 2, ... down to the first cell <= smallest_mm (500 .. 1.95 mm: 9 octaves
// by default), amplitude gain^k for octave k (2-D noise in the face's own coordinates for planar
// faces and cylinder caps, 3-D noise for spheres and cylinder sides); tint = 0.85 + 0.3 * (value noise of 300
// mm cells, its own per channel), so every channel is textured. Every face of every object has its own seed.
// Edge patterns are exactly `dark` and `light` (no texture, no shading): a known contrast for the
// 10-90 % edge width.
//
// File format (JSON object; unknown keys are errors, except keys starting with '_' = comments):
//   "format": "omma-room"  (optional; if present must be this), "version": 1 (optional; only 1)
//   "light":  {"direction": [x, y, z] (towards the light; need not be unit), "ambient": 0..1}
//             optional, default {"direction": [0.3, 0.2, 1], "ambient": 0.55}
//   "travel": {"direction": [x, y, z], "speed_mm_s": S}: how the live sim:room source moves the rig
//             (back and forth along direction, peak speed S, sim_loop.h); optional: without it the
//             rig turns about +z
//   "room":   REQUIRED, the room, a box seen from inside: {"min": [x, y, z], "max": [x, y, z]} or
//             {"centre": [x, y, z], "size": [sx, sy, sz]}, "material": MATERIAL (walls), and
//             optional "floor", "ceiling": MATERIAL (default: the walls' material, other seeds)
//   "objects": [OBJECT, ...] (optional), each with "type", an optional "name" (for messages and
//             room_objects) and its fields:
//     box       "min"/"max" or "centre"/"size" (sizes > 0), "material"            (a solid)
//     sphere    "centre", "radius" > 0, "material"                                (a solid)
//     cylinder  "centre" (its middle), "axis": "x" | "y" | "z", "radius" > 0, "length" > 0,
//               "material"                                 (a solid: side and two flat caps)
//     card      a rectangle, both sides visible: "centre", "normal" (its front; need not be unit),
//               "up" (optional, default [0, 0, 1]; [1, 0, 0] for a card facing up or down; projected
//               on the card's plane: the card's up axis), "size": [width, height] > 0,
//               "rotate_deg" (optional, about the normal, counter-clockwise seen from the front),
//               and either "material" or "pattern": {"type": "edge", "angle_deg": A (-45 .. 45, the
//               edge's slant from the card's up axis towards its right), "dark": D, "light": L
//               (radiances, 0 .. 1000; default 0.03 and 0.8)}: dark left of the edge line through
//               the centre, light right of it (seen from the front)
//     grid      a card with holes, a lattice of bars (an occluder to see through by synthetic
//               aperture): the card's fields plus "bar_mm" > 0, "pitch_mm" > bar_mm, "bars":
//               "both" (default) | "vertical" | "horizontal", "material". Bars of width bar_mm are
//               centred on the card's centre and every pitch_mm along its right (vertical bars)
//               and up (horizontal bars) axes; zero thickness. A ray through the grid is blocked
//               with probability 1 - (1 - bar/pitch)^2 (both) or bar/pitch (one direction).
//   MATERIAL: {"colour": [r, g, b] (linear RGB 0 .. 1000, "color" also taken; default 0.5 grey),
//             "contrast": 0 .. 1 (default 0.5), "seed": integer >= 0 (default: from the surface's
//             index), "largest_mm" (default 500), "smallest_mm" (default 2; 0.01 <= smallest <=
//             largest <= 1e5, at most 24 octaves), "gain": (0, 1] (default 0.8)}
// Every length is in mm and bounded by kMaxSceneMm (scene.h). Validation (SceneError naming the file
// and the field, e.g. "room file 'my.json': objects[3] (\"pole\"): 'radius' must be > 0, got -5"):
// malformed JSON, missing or unknown fields, wrong types or lengths, negative or zero sizes,
// unknown types, and a rig centre (the origin) outside the room or inside a solid object.
//
// Intersections are analytic (slab test for boxes, quadratics for spheres and cylinders, planes for
// cards and grids), a plain loop over the primitives: exact in double precision. Rays starting
// inside a solid see its inside faces; rays starting outside the room see its outside.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "omma/sim/scene.h"

namespace omma::sim {

// The built-in room's file text (data/scenes/room.json as it was at build time).
const std::string& default_room_json();

// A room from the text of a room file; `source` names the file in error messages, `spec` is what
// Scene::spec() returns. Throws SceneError (see the file comment).
std::unique_ptr<Scene> make_room_scene_from_text(const std::string& json_text, const std::string& source,
                                                 const std::string& spec);
// The room file at `path`; an empty path is the built-in room (spec "room", else "room:PATH").
// Throws SceneError if the file is missing, unreadable or invalid.
std::unique_ptr<Scene> make_room_scene(const std::string& path = "");

// What a room holds, for measurements on it (sharpness targets, the grid occluder): one entry per
// object of the file, in file order (the room itself is not listed). Vectors in the scene frame, mm.
struct RoomObject {
  std::string name;            // as in the file ("" if none)
  std::string type;            // box, sphere, cylinder, card, grid
  std::string pattern;         // card: "edge" or "noise"; other types: ""
  Vec3 centre = Vec3::Zero();  // box: its centre; cylinder: the middle of its axis
  Vec3 size = Vec3::Zero();    // box: extents; sphere: diameter x3; cylinder: diameter, diameter,
                               // length; card/grid: width, height, 0
  // Cards and grids: unit normal (front), right and up axes of the card (after rotate_deg).
  Vec3 normal = Vec3::Zero(), right = Vec3::Zero(), up = Vec3::Zero();
  // Edge cards: the unit direction of the edge line (through centre), and its slant in degrees.
  Vec3 edge = Vec3::Zero();
  double edge_angle_deg = 0;
  double dark = 0, light = 0;       // edge cards: the two radiances
  double bar_mm = 0, pitch_mm = 0;  // grids
};
// The objects of a room scene (as make_scene("room...") returns it); empty for other scenes.
std::vector<RoomObject> room_objects(const Scene& scene);

}  // namespace omma::sim
