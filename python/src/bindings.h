// The parts of the omma Python module (python/omma/__init__.py re-exports them). Each add_*
// function registers its classes and functions on the extension module `omma._omma`.
#pragma once

#include <string>

#include <nlohmann/json.hpp>
#include <pybind11/pybind11.h>
#include <pybind11/stl/filesystem.h>

namespace omma::py {

namespace py = pybind11;

void add_errors(py::module_& m);  // omma.Error and its subclasses, C++ exception translation
void add_rig(
    py::module_& m);  // Rig, load_rig (files and built-in names), thesis_prototype_rig, design, rig_diff
void add_sim(py::module_& m);     // SimulateOptions, simulate, Simulation
void add_pano(py::module_& m);    // stitch, evaluate, images, frames folders, calibrate
void add_engine(py::module_& m);  // Engine
void add_io(py::module_& m);      // Recording, FrameSet, record, render, export_pto, import_pto
void add_live(py::module_& m);    // run, LiveRun
void add_design(py::module_& m);  // plan, table71, builtin_rig_names

// A new exception type `name` ("omma.X") deriving from omma.Error (the first one made) and `builtin`
// (nullptr: Exception), with __text_signature__ "(*args)" and `doc` as its __doc__.
PyObject* make_error(const char* name, PyObject* builtin, const char* doc);

// JSON <-> Python objects (through Python's json module: exact for what rigs and summaries hold).
py::object to_python(const nlohmann::json& j);
nlohmann::json from_python(const py::handle& obj);

// A cache_dir= argument: None -> the default map cache (render::default_cache_dir), False -> ""
// (no cache), else a folder (str or os.PathLike).
std::string cache_dir_from_python(const py::object& cache_dir);

// Sets attributes of `options` (a bound options object) from keyword arguments; an unknown name
// raises TypeError listing the valid ones.
void set_fields(py::object options, const py::kwargs& kwargs, const std::string& function);

}  // namespace omma::py
