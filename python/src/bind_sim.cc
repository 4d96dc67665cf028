// The dome simulator for Python: camera frames and ground truth as NumPy arrays.
#include <memory>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "omma/core/grid.h"
#include "omma/sim/simulate.h"

namespace omma::py {

namespace {

// What simulate() returns: the result with the scene and options it came from (save() needs them).
struct Simulation {
  std::shared_ptr<sim::Scene> scene;
  sim::SimulateOptions options;
  sim::SimulateSummary result;
};

py::list frame_list(const Simulation& s, cv::Mat sim::CameraFrame::*field) {
  py::list out;
  for (const auto& f : s.result.frames) out.append(array_from_mat(f.*field));
  return out;
}

}  // namespace

void add_sim(py::module_& m) {
  py::class_<sim::CameraEffects>(
      m, "CameraEffects",
      "Sensor effects of the simulator (omma/sim/render.h); simulate() takes its fields "
      "as keyword arguments.")
      .def(py::init<>())
      .def_readwrite("supersample", &sim::CameraEffects::supersample)
      .def_readwrite("exposure", &sim::CameraEffects::exposure)
      .def_readwrite("vignetting", &sim::CameraEffects::vignetting)
      .def_readwrite("color_gain", &sim::CameraEffects::color_gain)
      .def_readwrite("full_scale_electrons", &sim::CameraEffects::full_scale_electrons)
      .def_readwrite("read_noise_dn", &sim::CameraEffects::read_noise_dn)
      .def_readwrite("bits", &sim::CameraEffects::bits)
      .def_readwrite("seed", &sim::CameraEffects::seed);

  py::class_<Simulation>(m, "Simulation", "What simulate() rendered. Images are BGR, as OpenCV's.")
      .def_property_readonly(
          "frames", [](const Simulation& s) { return frame_list(s, &sim::CameraFrame::image); },
          "Camera frames, uint8 (H, W, 3) sRGB, in rig order (shares the rendered buffers, no copy).")
      .def_property_readonly(
          "signals", [](const Simulation& s) { return frame_list(s, &sim::CameraFrame::signal); },
          "Linear sensor signals, float32 (H, W, 3) in [0, 1].")
      .def_property_readonly(
          "raw", [](const Simulation& s) { return frame_list(s, &sim::CameraFrame::raw); },
          "RGGB Bayer mosaics, uint16 (H, W), 0 .. 2^bits - 1 (None per camera unless raw=True).")
      .def_property_readonly(
          "truth", [](const Simulation& s) { return array_from_mat(s.result.truth); },
          "Ideal panorama seen from the dome centre, uint8 (H, W, 3) sRGB (None with truth=False).")
      .def_property_readonly("nominal_rig", [](const Simulation& s) { return s.result.nominal; })
      .def_property_readonly(
          "true_rig", [](const Simulation& s) { return s.result.true_rig; },
          "The rig the frames were rendered with (perturbed if perturb was given).")
      .def_property_readonly(
          "summary",
          [](const Simulation& s) {
            return to_python(sim::simulation_summary(s.result, s.options, *s.scene));
          },
          "What was simulated (the content of sim.json).")
      .def(
          "save",
          [](const Simulation& s, const std::filesystem::path& dir) {
            py::gil_scoped_release release;
            sim::write_frames_folder(dir, s.result, s.options, *s.scene);
          },
          py::arg("dir"),
          "Writes the frames folder (cam_XX.png, truth.png, rig.json, ...) as `omma simulate --out`.");

  m.def(
      "simulate",
      [](const Rig& rig, const py::object& scene, const std::string& projection, const py::object& size,
         uint64_t seed, bool ideal, int supersample, bool truth, int truth_supersample, bool raw,
         const std::string& perturb, double dome_z_mm, bool progress, const py::kwargs& effects) {
        auto s = std::make_unique<Simulation>();
        if (py::isinstance<py::str>(scene)) {
          s->scene = sim::make_scene(scene.cast<std::string>());
        } else {
          ImageSpec spec;
          spec.allow_bgra = true;
          s->scene = sim::make_photo_scene(mat_from_array(scene, "scene", spec));  // converted, not kept
        }
        sim::SimulateOptions& o = s->options;
        o.effects = ideal ? sim::CameraEffects::ideal(supersample) : sim::CameraEffects{};
        o.effects.supersample = supersample;
        o.effects.seed = seed;
        set_fields(py::cast(&o.effects, py::return_value_policy::reference), effects, "simulate");
        const cv::Size ts = size_from_python(size);
        o.truth_grid = PanoGrid{parse_projection(projection), ts.width, ts.height};
        o.truth = truth;
        o.truth_supersample = truth_supersample;
        o.raw = raw;
        o.perturb = sim::parse_perturb(perturb);
        o.pose.translation_mm = Vec3(0, 0, dome_z_mm);
        o.progress = progress;
        {
          py::gil_scoped_release release;
          s->result = sim::simulate(rig, *s->scene, o);
        }
        return s;
      },
      py::arg("rig"), py::arg("scene") = "colon", py::arg("projection") = "vr180",
      py::arg("size") = py::make_tuple(1080, 1080), py::arg("seed") = 1, py::arg("ideal") = false,
      py::arg("supersample") = 3, py::arg("truth") = true, py::arg("truth_supersample") = 0,
      py::arg("raw") = false, py::arg("perturb") = "", py::arg("dome_z_mm") = 0.0,
      py::arg("progress") = false,
      "Renders every camera of `rig` looking at `scene` and the ground-truth panorama (as `omma simulate`).\n"
      "scene: 'colon', 'photo:PATH', 'usaf[:MM]', 'checker[:MM]', or an equirectangular 360x180 photo as an\n"
      "array (BGR uint8/uint16/float32). projection/size: the truth's grid. ideal: no vignetting, gains, "
      "noise\n"
      "or quantisation. Further keyword arguments set CameraEffects fields (vignetting, color_gain,\n"
      "full_scale_electrons, read_noise_dn, bits, exposure). perturb: e.g. 'orient=0.5,focal=0.02'.");
}

}  // namespace omma::py
