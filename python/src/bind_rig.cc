// Rigs (load, validate, save, JSON), dome design and rig comparison for Python.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "omma/calib/rig_diff.h"
#include "omma/core/rig.h"
#include "omma/design/placement.h"
#include "omma/design/prototype.h"

namespace omma::py {

namespace {

py::dict stat_dict(const calib::Stat& s) {
  py::dict d;
  d["median"] = s.median;
  d["mean"] = s.mean;
  d["max"] = s.max;
  return d;
}

// A rig file, or a built-in rig by name: the resolver of the command line's --rig.
Rig load_rig_spec(const py::object& path) {
  const std::string spec = py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
  py::gil_scoped_release release;
  return design::load_rig_or_builtin(spec);
}

}  // namespace

void add_rig(py::module_& m) {
  py::class_<Rig>(m, "Rig",
                  "A dome of cameras (omma/core/rig.h): JSON in millimetres and degrees. Build one with "
                  "Rig.load, Rig.from_json, Rig.from_dict, design() or thesis_prototype_rig().")
      .def_static(
          "load", &load_rig_spec, py::arg("path"),
          "Loads and validates a rig file (RigError naming the field at fault), or a built-in rig by\n"
          "name as every --rig takes it (thesis-24, gigaeye-44, gigaeye-44-skip1, ...: "
          "builtin_rig_names()).")
      .def_static(
          "from_json", [](const std::string& text) { return rig_from_json(nlohmann::json::parse(text)); },
          py::arg("text"), "Parses and validates rig JSON text.")
      .def_static(
          "from_dict", [](const py::dict& d) { return rig_from_json(from_python(d)); }, py::arg("d"),
          "Builds and validates a rig from the dict of its JSON (as to_dict() gives).")
      .def(
          "to_dict", [](const Rig& r) { return to_python(rig_to_json(r)); }, "The rig's JSON as a dict.")
      .def(
          "to_json", [](const Rig& r, int indent) { return rig_to_json(r).dump(indent); },
          py::arg("indent") = 2, "The rig's JSON text (what save() writes).")
      .def(
          "save", [](const Rig& r, const std::filesystem::path& path) { save_rig(r, path); }, py::arg("path"),
          "Writes the rig file atomically (temporary file, then rename).")
      .def("validate", &Rig::validate, "Raises RigError if anything is inconsistent.")
      .def_property_readonly("name", [](const Rig& r) { return r.name; })
      .def_property_readonly("camera_ids",
                             [](const Rig& r) {
                               std::vector<int> ids;
                               for (const auto& c : r.cameras) ids.push_back(c.id);
                               return ids;
                             })
      .def_property_readonly(
          "camera_sizes",
          [](const Rig& r) {
            std::vector<std::pair<int, int>> s;
            for (const auto& c : r.cameras) s.emplace_back(c.in.width, c.in.height);
            return s;
          },
          "(width, height) of every camera, in rig order.")
      .def("__len__", [](const Rig& r) { return r.cameras.size(); })
      .def("__repr__", [](const Rig& r) {
        return fmt::format("<omma.Rig '{}': {} cameras{}>", r.name, r.cameras.size(),
                           r.dome.sphere ? ", sphere" : "");
      });

  m.def("load_rig", &load_rig_spec, py::arg("path"), "Rig.load(path): a rig file or a built-in rig's name.");
  m.def("thesis_prototype_rig", &design::thesis_prototype_rig,
        "The thesis's 24-camera prototype (max-volume, 1x1x2 mm cameras, 5 mm dome; 'thesis-24').");

  py::class_<design::Design>(m, "Design", "A designed rig: the rig, cameras per layer, and its R_vir.")
      .def_readonly("rig", &design::Design::rig)
      .def_readonly("layers", &design::Design::layers)
      .def_readonly("r_virtual_mm", &design::Design::r_virtual_mm)
      .def("__repr__", [](const design::Design& d) {
        return fmt::format("<omma.Design {} cameras, layers {}, R_vir {:.2f} mm>", d.rig.cameras.size(),
                           fmt::join(d.layers, "+"), d.r_virtual_mm);
      });
  m.def(
      "design",
      [](const std::string& method, double aov_deg, double r_phys_mm, const std::string& cam_size,
         double r_virtual_mm, bool sphere, const py::object& size, bool compute_r_virtual) {
        design::DesignParams p;
        p.aov_rad = deg2rad(aov_deg);
        p.r_phys_mm = r_phys_mm;
        p.cam = design::parse_camera_size(cam_size);
        p.r_virtual_mm = r_virtual_mm;
        p.sphere = sphere;
        const cv::Size s = size_from_python(size);
        p.width = s.width;
        p.height = s.height;
        p.compute_r_virtual = compute_r_virtual;
        const design::Method meth = design::parse_method(method);
        py::gil_scoped_release release;
        return design::design_rig(meth, p);
      },
      py::arg("method") = "max-volume", py::arg("aov_deg") = 64.0, py::arg("r_phys_mm") = 5.0,
      py::arg("cam_size") = "1x1x2", py::arg("r_virtual_mm") = 18.0, py::arg("sphere") = false,
      py::arg("size") = py::make_tuple(250, 250), py::arg("compute_r_virtual") = true,
      "Places cameras on a dome (thesis §3.3-3.4), as `omma design`: method layered | min-cameras | "
      "max-volume | cvt; cam_size 'WxHxL' in mm (max-volume); size (width, height) of every camera.");

  m.def(
      "rig_diff",
      [](const Rig& a, const Rig& b, bool align) {
        const calib::RigDiff d = calib::diff_rigs(a, b, align);
        py::dict out;
        out["orientation_error_deg"] = stat_dict(d.orientation_error_deg);
        out["focal_error_rel"] = stat_dict(d.focal_error_rel);
        out["center_error_px"] = stat_dict(d.center_error_px);
        out["ray_error_deg"] = stat_dict(d.ray_error_deg);
        out["per_camera_orientation_deg"] = d.per_camera_orientation_deg;
        return out;
      },
      py::arg("a"), py::arg("b"), py::arg("align") = false,
      "Camera-by-camera errors of rig a against rig b (as `omma rig-diff`): orientation, focal, centre and "
      "ray errors (median, mean, max).");
}

}  // namespace omma::py
