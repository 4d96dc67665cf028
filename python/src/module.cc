// The omma Python extension module: PYBIND11_MODULE and the error types.
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "bindings.h"
#include "omma/core/io.h"
#include "omma/core/log.h"
#include "omma/core/progress.h"
#include "omma/core/rig.h"
#include "omma/core/version.h"
#include "omma/live/sinks.h"
#include "omma/render/compiled_map.h"
#include "omma/sim/scene.h"

namespace omma::py {

py::object to_python(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

nlohmann::json from_python(const py::handle& obj) {
  const std::string text = py::module_::import("json").attr("dumps")(obj).cast<std::string>();
  return nlohmann::json::parse(text);
}

std::string cache_dir_from_python(const py::object& cache_dir) {
  if (cache_dir.is_none()) return render::default_cache_dir().string();
  if (py::isinstance<py::bool_>(cache_dir) && !cache_dir.cast<bool>()) return "";
  return py::str(py::module_::import("os").attr("fspath")(cache_dir)).cast<std::string>();
}

void set_fields(py::object options, const py::kwargs& kwargs, const std::string& function) {
  for (const auto& [key, value] : kwargs) {
    const std::string name = py::str(key);
    if (name.empty() || name[0] == '_' || !py::hasattr(options, name.c_str())) {
      std::string valid;
      for (const auto& attr : py::module_::import("builtins").attr("dir")(options)) {
        const std::string a = py::str(attr);
        if (a[0] != '_') valid += (valid.empty() ? "" : ", ") + a;
      }
      throw py::type_error(
          fmt::format("{}() got an unexpected keyword argument '{}' (options: {})", function, name, valid));
    }
    options.attr(name.c_str()) = value;
  }
}

PyObject* make_error(const char* name, PyObject* builtin, const char* doc) {
  // The docstring starts with "Name(*args)\n--\n\n" so that the type has a __text_signature__
  // (inspect.signature(omma.RigError) works); __doc__ is then set to the plain text.
  const std::string qual = name;
  const std::string short_name = qual.substr(qual.rfind('.') + 1);
  const std::string sig_doc = short_name + "(*args)\n--\n\n" + doc;
  static PyObject* base = nullptr;
  PyObject* bases = nullptr;
  if (builtin) bases = base ? PyTuple_Pack(2, base, builtin) : PyTuple_Pack(1, builtin);
  PyObject* type = PyErr_NewExceptionWithDoc(name, sig_doc.c_str(), bases, nullptr);
  Py_XDECREF(bases);
  if (!type) throw py::error_already_set();
  if (PyObject_SetAttrString(type, "__doc__", py::str(doc).ptr()) < 0) throw py::error_already_set();
  if (!base) base = type;  // the first one made is omma.Error, the base of the others
  return type;
}

void add_errors(py::module_& m) {
  // omma.Error is the base of every omma error; the subclasses also derive from the built-in
  // exception a Python caller would expect (a bad rig is a ValueError, a missing file an OSError).
  static PyObject* error = make_error("omma.Error", nullptr, "Base class of omma's errors.");
  auto make = [&](const char* name, PyObject* builtin, const char* doc) {
    return make_error(name, builtin, doc);
  };
  static PyObject* rig_error =
      make("omma.RigError", PyExc_ValueError, "An invalid rig (file, JSON or camera).");
  static PyObject* io_error = make("omma.IoError", PyExc_OSError, "A file that cannot be read or written.");
  static PyObject* scene_error = make("omma.SceneError", PyExc_ValueError, "An unknown or unreadable scene.");
  static PyObject* sink_error = make("omma.SinkError", PyExc_OSError, "An output that cannot be written.");
  m.add_object("Error", py::handle(error));
  m.add_object("RigError", py::handle(rig_error));
  m.add_object("IoError", py::handle(io_error));
  m.add_object("SceneError", py::handle(scene_error));
  m.add_object("SinkError", py::handle(sink_error));
  // The messages are those the command line prints after "omma: error: ".
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const RigError& e) {
      PyErr_SetString(rig_error, e.what());
    } catch (const IoError& e) {
      PyErr_SetString(io_error, e.what());
    } catch (const sim::SceneError& e) {
      PyErr_SetString(scene_error, e.what());
    } catch (const live::SinkError& e) {
      PyErr_SetString(sink_error, e.what());
    } catch (const nlohmann::json::exception& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const cv::Exception& e) {
      PyErr_SetString(error, e.what());
    }
  });
}

}  // namespace omma::py

PYBIND11_MODULE(_omma, m) {
  m.doc() =
      "omma: compound-eye camera toolkit (rigs, design, simulator, stitcher, real-time engine, calibration)";
  m.attr("__version__") = omma::version();
  omma::init_logging(false, false);  // "[info] ..." on stderr, as the command line
  omma::py::add_errors(m);
  omma::py::add_rig(m);
  omma::py::add_sim(m);
  omma::py::add_pano(m);
  omma::py::add_engine(m);
  omma::py::add_io(m);
  omma::py::add_live(m);
  omma::py::add_design(m);
  m.def(
      "set_verbosity",
      [](const std::string& level) {
        if (level != "quiet" && level != "info" && level != "debug")
          throw std::invalid_argument("verbosity must be quiet, info or debug (got '" + level + "')");
        spdlog::set_level(level == "debug"   ? spdlog::level::debug
                          : level == "quiet" ? spdlog::level::warn
                                             : spdlog::level::info);
        omma::set_progress_enabled(level != "quiet");
      },
      pybind11::arg("level"),
      "What omma writes to stderr: 'info' (default: log lines and progress bars of long operations),\n"
      "'quiet' (warnings and errors only, no progress) or 'debug'.");
}
