// The real-time engine for Python: omma.Engine(rig, method=..., size=...).render(frames).
// The map is compiled (or loaded from the cache) once, in the constructor; render() copies the
// frames into the engine's frame store and runs the C++ renderer into a NumPy array, with the GIL
// released (other Python threads run meanwhile; one Engine renders one call at a time).
#include <chrono>
#include <mutex>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "omma/render/compiled_map.h"
#include "omma/render/render.h"

namespace omma::py {

namespace {

render::Kernel parse_kernel(const std::string& name) {
  for (auto k :
       {render::Kernel::kAuto, render::Kernel::kScalar, render::Kernel::kAvx2, render::Kernel::kAvx512Vnni})
    if (render::to_string(k) == name) return k;
  throw std::invalid_argument("unknown kernel '" + name + "' (use auto, scalar, avx2 or avx512-vnni)");
}

class Engine {
 public:
  Engine(Rig rig, const std::string& method, const std::string& projection, const py::object& size,
         int threads, const py::object& cache_dir, double min_weight, const std::string& kernel)
      : rig_(std::move(rig)) {
    rig_.validate();
    if (rig_.cameras.empty()) throw RigError("the rig has no cameras");
    const cv::Size s = size_from_python(size);
    opt_.grid = PanoGrid{parse_projection(projection), s.width, s.height};
    opt_.method = pano::parse_method(method);
    opt_.min_weight = min_weight;
    std::string why;
    if (!opt_.IsValid(&why)) throw std::invalid_argument(why);
    render_.threads = threads;
    render_.kernel = parse_kernel(kernel);
    if (!render_.IsValid(&why)) throw std::invalid_argument(why);
    const std::string cache = cache_dir.is_none() ? std::string() : py::str(cache_dir).cast<std::string>();
    py::gil_scoped_release release;
    load_ = render::compile_map_cached(rig_, opt_, cache);
    store_ = render::FrameStore(load_.map.layout);
  }

  // Copies the frames into the store (no Python objects touched: call without the GIL).
  void set_frames_locked(const std::vector<cv::Mat>& frames) {
    for (size_t c = 0; c < frames.size(); ++c) store_.set(int(c), frames[c]);
    have_frames_ = true;
  }

  std::vector<cv::Mat> frames_arg(const py::object& frames, std::vector<py::object>* keep) const {
    ImageSpec spec;
    spec.allow_bgra = true;
    return frames_from_python(frames, rig_, spec, keep);
  }

  void set_frames(const py::object& frames) {
    std::vector<py::object> keep;
    const auto f = frames_arg(frames, &keep);
    py::gil_scoped_release release;
    std::lock_guard lock(mu_);
    set_frames_locked(f);
  }

  py::array render(const py::object& frames, const py::object& out) {
    std::vector<py::object> keep;
    std::vector<cv::Mat> f;
    if (!frames.is_none()) f = frames_arg(frames, &keep);
    py::array result;
    cv::Mat target;
    const int w = load_.map.width, h = load_.map.height;
    if (out.is_none()) {
      result = py::array_t<uint8_t>({h, w, 3});
      target = cv::Mat(h, w, CV_8UC3, result.mutable_data());
    } else {
      ImageSpec spec;
      spec.allow_u16 = spec.allow_f32 = spec.allow_gray = false;
      target = mat_from_array(out, "out", spec);
      result = py::reinterpret_borrow<py::array>(out);
      if (!result.writeable()) throw py::value_error("out is read-only");
      if (target.cols != w || target.rows != h)
        throw py::value_error(
            fmt::format("out is {}x{} (W x H), the engine renders {}x{}", target.cols, target.rows, w, h));
    }
    const uint8_t* const data = target.data;
    {
      py::gil_scoped_release release;
      std::lock_guard lock(mu_);
      if (!f.empty()) set_frames_locked(f);
      if (!have_frames_)
        throw std::invalid_argument("no frames yet: pass frames to render() or set_frames() first");
      render::render(load_.map, store_, target, render_);
    }
    if (target.data != data) throw std::logic_error("Engine.render: the output was reallocated");
    return result;
  }

  // Seconds for `iterations` renders in a C++ loop (frames, if given, copied in each time, as
  // render(frames) does): the peer of a Python loop over render() in benchmarks.
  double render_loop(int iterations, const py::object& frames) {
    std::vector<py::object> keep;
    std::vector<cv::Mat> f;
    if (!frames.is_none()) f = frames_arg(frames, &keep);
    py::gil_scoped_release release;
    std::lock_guard lock(mu_);
    if (f.empty() && !have_frames_)
      throw std::invalid_argument("no frames yet: pass frames or call set_frames() first");
    cv::Mat out(load_.map.height, load_.map.width, CV_8UC3);
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < iterations; ++i) {
      if (!f.empty()) set_frames_locked(f);
      render::render(load_.map, store_, out, render_);
    }
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

  const Rig& rig() const { return rig_; }
  const render::MapOptions& options() const { return opt_; }
  const render::MapLoad& load() const { return load_; }
  const render::RenderOptions& render_options() const { return render_; }

 private:
  Rig rig_;
  render::MapOptions opt_;
  render::RenderOptions render_;
  render::MapLoad load_;
  render::FrameStore store_;
  bool have_frames_ = false;
  std::mutex mu_;
};

}  // namespace

void add_engine(py::module_& m) {
  py::class_<Engine>(
      m, "Engine",
      "The real-time renderer (omma/engine): compiles the map of (rig, method, projection, size) once,\n"
      "then render(frames) gives each panorama at the C++ engine's speed, the GIL released.\n"
      "Frames: one uint8 BGR (H, W, 3) image per rig camera (uint16, float32 [0,1], gray and BGRA\n"
      "are converted), as a list or an (N, H, W, 3) array. Output: uint8 (height, width, 3) BGR.")
      .def(py::init<Rig, std::string, std::string, py::object, int, py::object, double, std::string>(),
           py::arg("rig"), py::arg("method") = "mrf", py::arg("projection") = "vr180",
           py::arg("size") = py::make_tuple(1080, 1080), py::arg("threads") = 0,
           py::arg("cache_dir") = py::none(), py::arg("min_weight") = 1.0 / 20, py::arg("kernel") = "auto",
           "threads: renderer threads (0 = all); cache_dir: folder of cached maps (None: always compile);\n"
           "min_weight: mrf-family taps below this fraction of a pixel's weight are dropped (MapOptions);\n"
           "kernel: auto | scalar | avx2 | avx512-vnni.")
      .def("render", &Engine::render, py::arg("frames") = py::none(), py::arg("out") = py::none(),
           "Renders one panorama from `frames` (or the frames last given) into a new array, or into `out`\n"
           "(uint8 (height, width, 3), written in place and returned).")
      .def("set_frames", &Engine::set_frames, py::arg("frames"),
           "Copies the frames into the engine's frame store.")
      .def("_render_loop", &Engine::render_loop, py::arg("iterations"), py::arg("frames") = py::none(),
           "Benchmark helper: seconds for `iterations` renders in a C++ loop (frames copied in each time if "
           "given).")
      .def_property_readonly("rig", &Engine::rig)
      .def_property_readonly("width", [](const Engine& e) { return e.load().map.width; })
      .def_property_readonly("height", [](const Engine& e) { return e.load().map.height; })
      .def_property_readonly("method", [](const Engine& e) { return pano::to_string(e.options().method); })
      .def_property_readonly("projection",
                             [](const Engine& e) { return to_string(e.options().grid.projection); })
      .def_property_readonly(
          "map_seconds", [](const Engine& e) { return e.load().seconds; },
          "Seconds to compile (or load) the map.")
      .def_property_readonly("map_from_cache", [](const Engine& e) { return e.load().from_cache; })
      .def_property_readonly(
          "bytes_per_pixel", [](const Engine& e) { return e.load().map.bytes_per_pixel(); },
          "Map bytes per output pixel.")
      .def_property_readonly("taps_per_pixel",
                             [](const Engine& e) {
                               const auto& map = e.load().map;
                               return double(map.taps()) / (double(map.width) * map.height);
                             })
      .def_property_readonly(
          "kernel",
          [](const Engine& e) {
            const auto k = e.render_options().kernel;
            return render::to_string(
                k == render::Kernel::kAuto || !render::kernel_available(k) ? render::best_kernel() : k);
          })
      .def("__repr__", [](const Engine& e) {
        return fmt::format("<omma.Engine {} {} {}x{}, {} cameras, {:.1f} B/px>",
                           pano::to_string(e.options().method), to_string(e.options().grid.projection),
                           e.load().map.width, e.load().map.height, e.rig().cameras.size(),
                           e.load().map.bytes_per_pixel());
      });
}

}  // namespace omma::py
