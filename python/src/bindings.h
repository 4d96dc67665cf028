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
void add_rig(py::module_& m);     // Rig, load_rig, thesis_prototype_rig, design, rig_diff
void add_sim(py::module_& m);     // SimulateOptions, simulate, Simulation
void add_pano(py::module_& m);    // stitch, evaluate, images, frames folders, calibrate
void add_engine(py::module_& m);  // Engine

// JSON <-> Python objects (through Python's json module: exact for what rigs and summaries hold).
py::object to_python(const nlohmann::json& j);
nlohmann::json from_python(const py::handle& obj);

// Sets attributes of `options` (a bound options object) from keyword arguments; an unknown name
// raises TypeError listing the valid ones.
void set_fields(py::object options, const py::kwargs& kwargs, const std::string& function);

}  // namespace omma::py
