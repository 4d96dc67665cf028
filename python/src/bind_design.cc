// The Giga-Eye recording planner for Python: omma.plan(...) and omma.table71(), the peers of
// `omma plan` and `omma plan --table71` (design/recording_plan.h; the dicts are the commands' JSON).
#include <optional>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "omma/design/prototype.h"
#include "omma/design/recording_plan.h"

namespace omma::py {

namespace {

// `omma plan --json` (RecordingPlan::to_json) and "failed": the failed checks in words.
py::dict plan_dict(const design::RecordingPlan& p) {
  py::dict d = to_python(p.to_json());
  d["failed"] = p.failed();
  return d;
}

// A size in bytes: a number, or text with units ("128GB", "150MB/s": design::parse_bytes).
double bytes_arg(const py::object& v, const char* what) {
  if (py::isinstance<py::str>(v)) return design::parse_bytes(v.cast<std::string>());
  if (py::isinstance<py::int_>(v) || py::isinstance<py::float_>(v)) return v.cast<double>();
  throw py::type_error(fmt::format("{} must be a number of bytes or text such as '128GB', got {}", what,
                                   py::repr(v).cast<std::string>()));
}

}  // namespace

void add_design(py::module_& m) {
  m.def(
      "plan",
      [](const py::object& row, const py::object& resolution, const py::object& bits, const py::object& fps,
         const py::object& clock_mhz, double max_clock_mhz, int cameras, int per_device,
         const py::object& device_size, const py::object& device_rate, const py::object& minutes) {
        design::RecordingPlanInput in;
        if (!row.is_none()) {
          const int r = row.cast<int>();
          if (r < 1 || r > 8)
            throw py::value_error(fmt::format("row must be 1..8 (Table 7.1's options), got {}", r));
          const design::RecordingPlanInput base = design::plan_input(design::table71()[size_t(r - 1)]);
          in.width = base.width, in.height = base.height, in.bits = base.bits, in.fps = base.fps;
          in.clock_mhz = base.clock_mhz, in.minutes = base.minutes;
        }
        if (!resolution.is_none() || row.is_none()) {
          const cv::Size s = size_from_python(
              resolution.is_none() ? py::object(py::str("2592x1944")) : resolution, "resolution");
          in.width = s.width, in.height = s.height;
        }
        if (!bits.is_none()) in.bits = bits.cast<int>();
        if (!fps.is_none()) in.fps = fps.cast<double>();
        if (!clock_mhz.is_none()) in.clock_mhz = clock_mhz.cast<double>();
        if (!minutes.is_none()) in.minutes = minutes.cast<double>();
        in.max_clock_mhz = max_clock_mhz;
        in.cameras = cameras;
        in.cameras_per_device = per_device;
        in.device_bytes = bytes_arg(device_size, "device_size");
        in.device_rate = bytes_arg(device_rate, "device_rate");
        return plan_dict(design::make_plan(in));
      },
      py::arg("row") = py::none(), py::arg("resolution") = py::none(), py::arg("bits") = py::none(),
      py::arg("fps") = py::none(), py::arg("clock_mhz") = py::none(), py::arg("max_clock_mhz") = 80.0,
      py::arg("cameras") = 44, py::arg("per_device") = 2, py::arg("device_size") = "128GB",
      py::arg("device_rate") = "150MB/s", py::arg("minutes") = py::none(),
      "The Giga-Eye recording plan (thesis Table 7.1), as `omma plan --json`: per camera, per storage "
      "device\n"
      "and for the rig, the bandwidth, the storage for `minutes` and the minutes a device holds, and the\n"
      "checks pixel-clock, pixel-rate, device-write-rate, device-capacity. row: start from Table 7.1 option\n"
      "1..8 (the other arguments given override it); without a row: 2592x1944, 12 bit, 9.5 fps, 66 MHz, 14\n"
      "min. device_size/device_rate: bytes or text ('128GB', '150MB/s', '1 TiB'). A plan that does not hold\n"
      "is returned with 'feasible': False and 'failed' naming the checks (`omma plan` exits 1).");
  m.def(
      "table71",
      [] {
        py::list rows;
        for (const auto& r : design::check_table71()) {
          py::dict d;
          d["option"] = r.row.option;
          d["printed_bandwidth_mb_s"] = r.row.bandwidth_mb_s;
          d["printed_memory_gb"] = r.row.memory_gb;
          d["bandwidth_mib_s"] = r.plan.camera_mib_per_s;
          d["memory_gib"] = r.plan.camera_gib;
          d["bandwidth_rounded"] = r.bandwidth;
          d["memory_rounded"] = r.memory;
          d["matches"] = r.matches;
          d["fits_bits"] = r.fits_bits ? py::object(py::int_(*r.fits_bits)) : py::object(py::none());
          d["plan"] = plan_dict(r.plan);
          rows.append(d);
        }
        return rows;
      },
      "Table 7.1 of the thesis recomputed row by row, as `omma plan --table71 --json`'s rows.");
  m.def("builtin_rig_names", &design::builtin_rig_names,
        "Names Rig.load and every --rig take besides files: thesis-24, gigaeye-44, gigaeye-44-skip1, ...");
}

}  // namespace omma::py
