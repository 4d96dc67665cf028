// Recordings (open, frame sets, record from sources), offline rendering to files (BigTIFF), and
// Hugin PTO import/export for Python: the peers of `omma recording check`, `omma record`,
// `omma render` and `omma pto`. Long calls release the GIL.
#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "omma/calib/pto.h"
#include "omma/core/frames.h"
#include "omma/core/grid.h"
#include "omma/core/io.h"
#include "omma/design/prototype.h"
#include "omma/io/pano_file.h"
#include "omma/io/point_cloud.h"
#include "omma/io/recording.h"
#include "omma/isp/color.h"
#include "omma/isp/demosaic.h"
#include "omma/isp/photometric.h"
#include "omma/live/recorder.h"
#include "omma/live/sources.h"
#include "omma/render/pano_render.h"

namespace omma::py {

namespace fs = std::filesystem;

namespace {

// One matched frame set of a recording (io::FrameSet) with its frames read.
struct PyFrameSet {
  int64_t index = 0;
  int64_t t_ns = 0;
  py::array_t<int64_t> frame_indices;  // per camera, -1 where the set lacks the camera
  py::array_t<int64_t> timestamps_ns;  // per camera: the frame's t_ns, -1 where missing
  py::list frames;                     // per camera: uint16 mosaic (raw) or uint8 BGR, None if missing
};

class Recording {
 public:
  explicit Recording(const fs::path& dir) : path_(dir) {
    py::gil_scoped_release release;
    reader_ = std::make_unique<io::RecordingReader>(dir);
  }
  const io::RecordingReader& reader() const { return *reader_; }
  const fs::path& path() const { return path_; }

  void check_cam(int cam) const {
    if (cam < 0 || cam >= reader_->cameras())
      throw py::index_error(fmt::format("camera index {} outside 0..{}", cam, reader_->cameras() - 1));
  }
  int64_t set_index(int64_t i) const {
    const int64_t n = reader_->frame_sets();
    if (i < 0) i += n;
    if (i < 0 || i >= n) throw py::index_error(fmt::format("frame set {} outside the recording's {}", i, n));
    return i;
  }

  py::array_t<int64_t> timestamps(int cam) const {
    check_cam(cam);
    const auto& m = reader_->meta(cam);
    py::array_t<int64_t> out(py::ssize_t(m.size()));
    auto* p = out.mutable_data();
    for (size_t i = 0; i < m.size(); ++i) p[i] = m[i].t_ns;
    return out;
  }
  py::array_t<uint64_t> sequence(int cam) const {
    check_cam(cam);
    const auto& m = reader_->meta(cam);
    py::array_t<uint64_t> out(py::ssize_t(m.size()));
    auto* p = out.mutable_data();
    for (size_t i = 0; i < m.size(); ++i) p[i] = m[i].seq;
    return out;
  }
  py::object read(int cam, int64_t i) const {
    check_cam(cam);
    if (i < 0) i += reader_->frames(cam);
    if (i < 0 || i >= reader_->frames(cam))
      throw py::index_error(
          fmt::format("frame {} outside camera index {}'s {} frames", i, cam, reader_->frames(cam)));
    cv::Mat m;
    {
      py::gil_scoped_release release;
      m = reader_->read(cam, i);
    }
    return array_from_mat(m);
  }

  PyFrameSet frame_set(int64_t i, bool develop, const std::string& demosaic, const std::string& awb,
                       bool photometric) const {
    i = set_index(i);
    const io::FrameSet& s = reader_->match().sets[size_t(i)];
    PyFrameSet out;
    out.index = i;
    out.t_ns = s.t_ns;
    const int n = reader_->cameras();
    out.frame_indices = py::array_t<int64_t>(n);
    out.timestamps_ns = py::array_t<int64_t>(n);
    for (int c = 0; c < n; ++c) {
      const int64_t f = c < int(s.frame.size()) ? s.frame[size_t(c)] : -1;
      out.frame_indices.mutable_data()[c] = f;
      out.timestamps_ns.mutable_data()[c] = f >= 0 ? reader_->meta(c)[size_t(f)].t_ns : -1;
    }
    std::vector<cv::Mat> frames;
    {
      py::gil_scoped_release release;
      if (develop) {
        isp::IspOptions iso;
        iso.demosaic = isp::parse_demosaic(demosaic);
        iso.awb = isp::parse_awb(awb);
        iso.srgb = true;
        const std::vector<cv::Mat> gains =
            photometric ? isp::flat_gains_from_rig(reader_->rig()) : std::vector<cv::Mat>{};
        frames = render::develop_frame_set(*reader_, i, iso, nullptr, gains);
        // develop_frame_set fills a missing camera with black: report it as missing (None).
        for (int c = 0; c < n; ++c)
          if (out.frame_indices.data()[c] < 0) frames[size_t(c)] = cv::Mat();
      } else {
        frames = reader_->read_frame_set(i);
      }
    }
    for (auto& f : frames) out.frames.append(array_from_mat(f));
    return out;
  }

 private:
  fs::path path_;
  std::unique_ptr<io::RecordingReader> reader_;
};

std::vector<std::string> source_specs(const py::object& source) {
  if (py::isinstance<py::str>(source)) return {source.cast<std::string>()};
  if (py::hasattr(source, "__fspath__")) return {py::str(source.attr("__fspath__")()).cast<std::string>()};
  std::vector<std::string> out;
  for (const auto& s : source) out.push_back(py::str(s).cast<std::string>());
  if (out.empty()) throw py::value_error("source: give at least one source spec");
  return out;
}

// "WxH" or (w, h) -> the renderer's size (banded: larger than one image may be).
Size2 banded_size(const py::object& size) {
  if (py::isinstance<py::str>(size)) return parse_size(size.cast<std::string>(), /*banded=*/true);
  if (py::isinstance<py::sequence>(size) && py::len(size) == 2) {
    try {
      const auto t = size.cast<std::pair<int64_t, int64_t>>();
      return parse_size(fmt::format("{}x{}", t.first, t.second), /*banded=*/true);
    } catch (const py::cast_error&) {
    }
  }
  throw py::value_error(fmt::format("size must be (width, height) with positive integers or \"WxH\", got {}",
                                    py::repr(size).cast<std::string>()));
}

py::dict render_files(const py::object& input, const fs::path& out, const py::object& rig_arg,
                      const py::object& size, const std::string& projection, const std::string& method,
                      const py::object& sets, int band_rows, const std::string& demosaic,
                      const std::string& awb, int bits, int threads, const py::object& cache_dir,
                      bool photometric, bool raw, double min_weight, const std::string& incomplete,
                      double hold_max_age_ms, bool progress) {
  render::PanoRenderOptions o;
  const Size2 s = banded_size(size);
  o.grid = PanoGrid{parse_projection(projection), s.width, s.height};
  if (method == "hq") {
    o.offline = true;
    o.method = pano::Method::kLinear;
  } else {
    o.method = pano::parse_method(method);
  }
  if (band_rows < 1) throw py::value_error("band_rows must be >= 1");
  o.band_rows = band_rows;
  o.min_weight = min_weight;
  o.render.threads = threads;
  o.progress = progress;
  o.cache_dir = cache_dir_from_python(cache_dir);
  if (std::string why; !o.IsValid(&why)) throw py::value_error(why);
  if (const std::string ext = lower_extension(out); ext != ".tif" && ext != ".tiff" && ext != ".btf")
    check_image_format(out, s.width, s.height);
  isp::IspOptions iso;
  iso.demosaic = isp::parse_demosaic(demosaic);
  iso.awb = isp::parse_awb(awb);
  iso.srgb = true;
  iso.bits = bits;

  // The input: a recording folder, a frames folder, or frames in memory (rig required).
  std::unique_ptr<io::RecordingReader> rec;
  std::vector<cv::Mat> mem_frames;
  std::vector<py::object> keep;
  Rig rig;
  bool from_folder = false;
  fs::path dir;
  const bool path_like = py::isinstance<py::str>(input) || py::hasattr(input, "__fspath__");
  if (path_like) {
    dir = py::str(py::module_::import("os").attr("fspath")(input)).cast<std::string>();
    if (fs::exists(dir / "manifest.json")) {
      py::gil_scoped_release release;
      rec = std::make_unique<io::RecordingReader>(dir);
    } else if (!fs::is_directory(dir)) {
      throw IoError("input '" + dir.string() + "' is neither a recording nor a frames folder");
    } else {
      from_folder = true;
    }
  }
  if (rec) {
    const Rig& rr = rec->manifest().rig;
    rig = rig_arg.is_none() ? rr : rig_arg.cast<Rig>();
    if (const std::string why = io::rig_mismatch(rig, rr); !why.empty()) throw py::value_error("rig " + why);
  } else if (from_folder) {
    rig = rig_arg.is_none() ? load_rig(dir / "rig.json") : rig_arg.cast<Rig>();
  } else {
    if (rig_arg.is_none()) throw py::value_error("rendering frames in memory needs rig=");
    rig = rig_arg.cast<Rig>();
    mem_frames = frames_from_python(input, rig, {}, &keep);
  }
  // Which frame sets.
  int64_t first = 0, last = rec ? rec->frame_sets() - 1 : 0;
  if (!sets.is_none()) {
    if (!rec) throw py::value_error("sets needs a recording");
    if (py::isinstance<py::int_>(sets)) {
      first = last = sets.cast<int64_t>();
    } else if (py::isinstance<py::slice>(sets)) {
      size_t start = 0, stop = 0, step = 0, len = 0;
      if (!sets.cast<py::slice>().compute(size_t(rec->frame_sets()), &start, &stop, &step, &len) || step != 1)
        throw py::value_error("sets: a slice with step 1");
      first = int64_t(start);
      last = int64_t(stop) - 1;
    } else {
      const auto t = sets.cast<std::pair<int64_t, int64_t>>();
      first = t.first;
      last = t.second - 1;
    }
    if (first < 0 || last < first || last >= rec->frame_sets())
      throw py::value_error(fmt::format("sets {} outside the recording's {} frame sets",
                                        py::repr(sets).cast<std::string>(), rec->frame_sets()));
  }
  if (rec && rec->frame_sets() == 0) throw py::value_error("the recording has no frame sets");

  // Sets lacking cameras, as `omma render --incomplete` (io::plan_frame_sets): held, skipped or refused,
  // never rendered with black cameras.
  io::FrameSetPlan plan;
  std::unique_ptr<io::PlannedFrameSets> planned;
  if (rec) {
    io::FrameSetPlanOptions po;
    po.policy = io::parse_incomplete_policy(incomplete);
    if (!(hold_max_age_ms >= 0 && hold_max_age_ms <= 3.6e6))
      throw py::value_error("hold_max_age_ms must be in [0, 3600000] (0: two frame-set periods)");
    po.max_hold_age_ns = int64_t(std::llround(hold_max_age_ms * 1e6));
    plan = rec->plan(first, last, po);  // raises RecordingError under "fail"
    planned = std::make_unique<io::PlannedFrameSets>(*rec, plan);
    if (plan.incomplete > 0)
      PyErr_WarnEx(
          PyExc_RuntimeWarning,
          fmt::format("{} of {} frame sets lack cameras (incomplete='{}'): {} completed with held frames, "
                      "{} skipped",
                      plan.incomplete, plan.considered, io::incomplete_policy_name(plan.policy),
                      plan.held_sets, plan.skipped)
              .c_str(),
          2);
    if (plan.sets.empty()) throw py::value_error("no frame set to render: every frame set lacks cameras");
  }
  const int64_t items = rec ? int64_t(plan.sets.size()) : 1;

  std::vector<std::string> outputs;
  double read_s = 0, develop_s = 0, render_s = 0, write_s = 0;
  size_t memory = 0;
  {
    py::gil_scoped_release release;
    std::vector<cv::Mat> gains;
    if (photometric && (rec || raw)) gains = isp::flat_gains_from_rig(rig);
    render::PanoRenderer renderer(rig, o);
    memory = renderer.memory().total();
    for (int64_t i = 0; i < items; ++i) {
      const int64_t set = rec ? plan.sets[size_t(i)].set : first;
      const fs::path path = io::frame_set_path(out.string(), set, last > first);
      if (rec) {
        const render::FrameSetTimes t = io::render_frame_set(*planned, i, renderer, iso, path);
        read_s += t.read, develop_s += t.develop, render_s += t.render, write_s += t.write;
      } else {
        std::vector<cv::Mat> frames;
        if (from_folder) {
          frames = raw ? load_raw_frames(dir, rig) : load_frames(dir, rig);
          if (raw)
            frames = isp::develop_with_model(frames, iso, gains);
          else if (photometric)
            frames = isp::correct_frames(rig, frames);
        } else {
          frames = photometric ? isp::correct_frames(rig, mem_frames) : mem_frames;
        }
        renderer.set_frames(frames);
        render_s += io::render_to_file(renderer, path);
      }
      outputs.push_back(path.string());
    }
  }
  py::dict d;
  d["outputs"] = outputs;
  d["frame_sets"] = rec ? py::object(py::int_(last - first + 1)) : py::object(py::none());
  d["incomplete"] = rec ? to_python(plan.to_json()) : py::object(py::none());
  d["width"] = s.width;
  d["height"] = s.height;
  d["projection"] = to_string(o.grid.projection);
  d["method"] = method;
  d["memory_bytes"] = memory;
  py::dict secs;
  secs["read"] = read_s;
  secs["develop"] = develop_s;
  secs["render"] = render_s;
  secs["write"] = write_s;
  d["seconds"] = secs;
  return d;
}

}  // namespace

void add_io(py::module_& m) {
  auto make = [&](const char* name, PyObject* builtin, const char* doc) {
    return make_error(name, builtin, doc);
  };
  static PyObject* recording_error =
      make("omma.RecordingError", PyExc_OSError, "A recording that cannot be created, read or trusted.");
  static PyObject* pto_error = make("omma.PtoError", PyExc_ValueError, "A Hugin project omma cannot read.");
  static PyObject* source_error =
      make("omma.SourceError", PyExc_OSError, "A camera source that cannot be opened.");
  m.add_object("RecordingError", py::handle(recording_error));
  m.add_object("PtoError", py::handle(pto_error));
  m.add_object("SourceError", py::handle(source_error));
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const io::RecordingError& e) {
      PyErr_SetString(recording_error, e.what());
    } catch (const calib::PtoError& e) {
      PyErr_SetString(pto_error, e.what());
    } catch (const live::SourceError& e) {
      PyErr_SetString(source_error, e.what());
    }
  });

  py::class_<PyFrameSet>(
      m, "FrameSet",
      "One matched frame set of a recording: at most one frame per camera, taken within half "
      "a period 1/fps of the set's instant t_ns (io/recording.h).")
      .def_readonly("index", &PyFrameSet::index, "The set's index in the recording.")
      .def_readonly(
          "t_ns", &PyFrameSet::t_ns,
          "The set's instant (a tick of the frame-set clock: every frame of the set lies within half a "
          "period 1/fps of it), ns since start_unix_ns.")
      .def_readonly("frame_indices", &PyFrameSet::frame_indices,
                    "int64 (N,): each camera's frame index in its stream, -1 where the set lacks the camera.")
      .def_readonly("timestamps_ns", &PyFrameSet::timestamps_ns,
                    "int64 (N,): each camera's capture time, ns since start_unix_ns; -1 where missing.")
      .def_readonly("frames", &PyFrameSet::frames,
                    "Per camera (rig order): uint16 (H, W) RGGB mosaic, or uint8 (H, W, 3) BGR when "
                    "developed; None where the set lacks the camera.")
      .def_property_readonly(
          "complete",
          [](const PyFrameSet& s) {
            const auto* p = s.frame_indices.data();
            for (py::ssize_t i = 0; i < s.frame_indices.size(); ++i)
              if (p[i] < 0) return false;
            return true;
          },
          "True when every camera has a frame in the set.")
      .def("__repr__", [](const PyFrameSet& s) {
        return fmt::format("<omma.FrameSet {} at {:.6f} s, {} frames>", s.index, s.t_ns / 1e9,
                           py::len(s.frames));
      });

  py::class_<Recording>(
      m, "Recording",
      "A raw multi-camera recording (HDF5 streams + manifest.json, io/recording.h), opened for "
      "random access (also while it is being written, or after a crash). A sequence of "
      "FrameSet: len(rec), rec[i], `for fs in rec`.")
      .def(py::init<fs::path>(), py::arg("path"),
           "Opens and checks the recording folder (RecordingError naming the camera and the file).")
      .def_property_readonly("path", [](const Recording& r) { return r.path(); })
      .def_property_readonly("rig", [](const Recording& r) { return r.reader().manifest().rig; })
      .def_property_readonly("cameras", [](const Recording& r) { return r.reader().cameras(); })
      .def_property_readonly(
          "fps", [](const Recording& r) { return r.reader().manifest().fps; },
          "Nominal frame rate: frames are matched within half of 1/fps.")
      .def_property_readonly("bits", [](const Recording& r) { return r.reader().manifest().bits; })
      .def_property_readonly("sensor_mode",
                             [](const Recording& r) { return r.reader().manifest().sensor_mode; })
      .def_property_readonly("clock_mhz", [](const Recording& r) { return r.reader().manifest().clock_mhz; })
      .def_property_readonly("start_unix_ns",
                             [](const Recording& r) { return r.reader().manifest().start_unix_ns; })
      .def_property_readonly(
          "complete", [](const Recording& r) { return r.reader().manifest().complete; },
          "True once the recorder closed it normally.")
      .def_property_readonly(
          "manifest", [](const Recording& r) { return to_python(r.reader().manifest().to_json()); },
          "manifest.json as a dict.")
      .def_property_readonly(
          "frame_counts",
          [](const Recording& r) {
            std::vector<int64_t> n;
            for (int c = 0; c < r.reader().cameras(); ++c) n.push_back(r.reader().frames(c));
            return n;
          },
          "Complete frames per camera (rig order).")
      .def_property_readonly("complete_sets",
                             [](const Recording& r) { return r.reader().match().complete_sets; })
      .def_property_readonly(
          "match_stats",
          [](const Recording& r) {
            py::list out;
            const auto& st = r.reader().match().cameras;
            for (size_t c = 0; c < st.size(); ++c) {
              py::dict d;
              d["camera"] = r.reader().manifest().rig.cameras[c].id;
              d["frames"] = st[c].frames;
              d["dropped"] = st[c].dropped;
              d["duplicates"] = st[c].duplicates;
              d["missing"] = st[c].missing;
              d["extra"] = st[c].extra;
              out.append(d);
            }
            return out;
          },
          "Per camera: frames, dropped (sequence gaps), duplicates, missing (sets without it), extra "
          "(as `omma recording check`).")
      .def("timestamps", &Recording::timestamps, py::arg("camera"),
           "int64 (frames,): capture times of camera index `camera`, ns since start_unix_ns.")
      .def("sequence", &Recording::sequence, py::arg("camera"),
           "uint64 (frames,): the source's sequence numbers of camera index `camera` (gaps = dropped).")
      .def("read", &Recording::read, py::arg("camera"), py::arg("frame"),
           "Frame `frame` of camera index `camera`: uint16 (H, W) RGGB mosaic, `bits` significant bits.")
      .def("frame_set", &Recording::frame_set, py::arg("index"), py::arg("develop") = false,
           py::arg("demosaic") = "hybrid", py::arg("awb") = "grayworld", py::arg("photometric") = true,
           "Frame set `index` with its frames read: raw mosaics, or with develop=True developed by the ISP\n"
           "(demosaic, white balance or the rig's photometric model, sRGB) into uint8 BGR frames that\n"
           "stitch(), Engine.render() and render() take.")
      .def("__len__", [](const Recording& r) { return r.reader().frame_sets(); })
      .def(
          "__getitem__",
          [](const Recording& r, int64_t i) { return r.frame_set(i, false, "hybrid", "grayworld", true); },
          py::arg("index"))
      .def("__repr__", [](const Recording& r) {
        return fmt::format("<omma.Recording '{}': {} cameras, {} frame sets, {:g} fps, {} bit{}>",
                           r.path().string(), r.reader().cameras(), r.reader().frame_sets(),
                           r.reader().manifest().fps, r.reader().manifest().bits,
                           r.reader().manifest().complete ? "" : ", not closed");
      });

  m.def(
      "record",
      [](const Rig& rig, const py::object& source, const fs::path& out, double duration, int64_t frames,
         const py::object& fps, const py::object& source_fps, const py::object& sensor_mode, double clock_mhz,
         int queue, double flush_s, bool progress) {
        if (duration <= 0 && frames <= 0) throw py::value_error("give duration or frames (or both)");
        live::RecordOptions o;
        o.duration_s = duration;
        o.frames = frames;
        o.queue_frames = queue;
        o.flush_interval_s = flush_s;
        o.fps = fps.is_none() ? 0.0 : fps.cast<double>();  // 0: derived from the sources' own rates
        o.clock_mhz = clock_mhz;
        o.sensor_mode = sensor_mode.is_none() ? rig.name : sensor_mode.cast<std::string>();
        o.progress = progress;
        if (std::string why; !o.IsValid(&why)) throw py::value_error(why);
        live::SourceOptions so;
        so.fps = !source_fps.is_none() ? source_fps.cast<double>()
                 : fps.is_none()       ? live::kFallbackFps
                                       : o.fps;
        so.sim.progress = progress;
        if (std::string why; !so.IsValid(&why)) throw py::value_error(why);
        const std::vector<std::string> specs = source_specs(source);
        // The recorder runs in its own thread; this one waits without the GIL and checks Python's
        // signals every 0.1 s: Ctrl-C stops the recording cleanly (what was recorded stays
        // readable, the manifest complete), then raises KeyboardInterrupt.
        live::RecordSummary s;
        std::atomic<bool> stop{false};
        o.stop = &stop;
        std::mutex mu;
        std::condition_variable cv;
        bool done = false;
        std::exception_ptr error;
        std::thread worker([&] {
          try {
            auto sources = live::open_sources(rig, specs, so);
            io::RecordingManifest mf;
            mf.rig = rig;
            s = live::record(std::move(sources), out, mf, o);
          } catch (...) {
            error = std::current_exception();
          }
          std::lock_guard lock(mu);
          done = true;
          cv.notify_all();
        });
        bool interrupted = false;
        for (;;) {
          {
            py::gil_scoped_release release;
            std::unique_lock lock(mu);
            if (cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return done; })) break;
          }
          if (!interrupted && PyErr_CheckSignals() != 0) {
            interrupted = true;  // the Python exception stays set until the recorder has stopped
            stop = true;
          }
        }
        {
          py::gil_scoped_release release;
          worker.join();
        }
        if (interrupted) throw py::error_already_set();
        if (error) std::rethrow_exception(error);
        py::dict d;
        d["out"] = out;
        d["cameras"] = rig.cameras.size();
        d["frames"] = s.frames;
        d["dropped"] = s.dropped;
        d["bytes"] = s.bytes;
        d["seconds"] = s.seconds;
        d["mb_per_s"] = s.mb_per_s();
        d["error"] = s.error.empty() ? py::object(py::none()) : py::object(py::str(s.error));
        if (!s.error.empty())
          PyErr_WarnEx(PyExc_RuntimeWarning,
                       ("omma.record: the recording stopped early: " + s.error +
                        " (what was recorded before is readable)")
                           .c_str(),
                       2);
        return d;
      },
      py::arg("rig"), py::arg("source"), py::arg("out"), py::arg("duration") = 0.0, py::arg("frames") = 0,
      py::arg("fps") = py::none(), py::arg("source_fps") = py::none(), py::arg("sensor_mode") = py::none(),
      py::arg("clock_mhz") = 0.0, py::arg("queue") = 4, py::arg("flush_s") = 0.5, py::arg("progress") = false,
      "Records free-running camera sources into the recording folder `out` (must not exist) as 12-bit RGGB\n"
      "mosaics with capture timestamps, as `omma record`: source is one spec for all cameras or one per "
      "camera\n"
      "(as omma.run: 'sim:colon', 'frames:DIR', 'pano:IMAGE', videos, image folders, ...). Stops after\n"
      "`duration` seconds and/or `frames` frames per camera. fps: the frame-set rate (None: 0.9 x the\n"
      "slowest camera's own rate, as `omma record`). Returns the summary dict (frames, dropped per\n"
      "camera, bytes, seconds, mb_per_s, error); an early stop (disk full) warns and sets 'error'. Ctrl-C\n"
      "(SIGINT) stops the recording cleanly, then raises KeyboardInterrupt.");

  m.def(
      "write_ply",
      [](const py::object& path, const py::object& depth, const py::object& colour,
         const std::string& projection, const py::object& q, int step, double min_confidence,
         const py::object& confidence) {
        auto floats = [](const py::object& a, const std::string& what) {
          const auto d = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
          if (!d || d.ndim() != 2) throw py::value_error(what + " must be a float (H, W) array");
          return cv::Mat(int(d.shape(0)), int(d.shape(1)), CV_32FC1, const_cast<float*>(d.data())).clone();
        };
        const cv::Mat D = floats(depth, "depth");
        ImageSpec spec;
        spec.allow_u16 = spec.allow_f32 = false;
        spec.allow_bgra = true;
        const cv::Mat C = mat_from_array(colour, "colour", spec);
        io::PointCloudOptions o;
        o.step = step;
        o.min_confidence = min_confidence;
        if (!q.is_none()) {
          const auto v = q.cast<std::vector<double>>();
          if (v.size() != 3) throw py::value_error("q must be (x, y, z) in mm");
          o.q = Vec3(v[0], v[1], v[2]);
        }
        const cv::Mat conf = confidence.is_none() ? cv::Mat() : floats(confidence, "confidence");
        const PanoGrid grid{parse_projection(projection), D.cols, D.rows};
        const io::PointCloud cloud = io::depth_to_points(D, C, grid, o, conf);
        io::write_ply(py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>(), cloud,
                      o.q);
        return cloud.size();
      },
      py::arg("path"), py::arg("depth"), py::arg("colour"), py::arg("projection") = "vr180",
      py::arg("q") = py::none(), py::arg("step") = 1, py::arg("min_confidence") = 0.0,
      py::arg("confidence") = py::none(),
      "Writes the coloured point cloud of a panorama's depth as binary PLY, as `omma stitch --ply`\n"
      "(io/point_cloud.h): X = q + D w per pixel in mm in the rig frame (+z the dome axis), float x y z and\n"
      "uchar red green blue. depth: float32 (H, W) mm along each pixel's direction from q (inf: no point);\n"
      "colour: the (H, W[, 3|4]) uint8 panorama (BGR, as cv2) of the same grid (projection); every step-th\n"
      "pixel in each axis; confidence: optional float32 (H, W), pixels below min_confidence left out.\n"
      "Written atomically. Returns the number of points.");

  m.def(
      "render", &render_files, py::arg("input"), py::arg("out"), py::arg("rig") = py::none(),
      py::arg("size") = py::make_tuple(9000, 2400), py::arg("projection") = "equirect-100",
      py::arg("method") = "mrf", py::arg("sets") = py::none(), py::arg("band_rows") = 256,
      py::arg("demosaic") = "hybrid", py::arg("awb") = "grayworld", py::arg("bits") = 12,
      py::arg("threads") = 0, py::arg("cache_dir") = py::none(), py::arg("photometric") = true,
      py::arg("raw") = false, py::arg("min_weight") = 1.0 / 20, py::arg("incomplete") = "hold",
      py::arg("hold_max_age_ms") = 0.0, py::arg("progress") = false,
      "Renders a panorama file band by band, as `omma render`: input is a recording folder (every frame "
      "set,\n"
      "or `sets`: an index, (first, stop) or a slice), a frames folder (cam_XX.png + rig.json; raw=True: "
      "16-bit\n"
      "mosaics developed by the ISP), or frames in memory (a list or (N, H, W, 3) array; rig= required).\n"
      "out: .tif/.tiff is written as BigTIFF (any size, memory = one band), other extensions through "
      "OpenCV;\n"
      "atomic; with several sets '{set}' in the name is replaced by the 5-digit index (else _00012 is "
      "added).\n"
      "method: nn | linear | gaussian | mrf | mrf-spherical | sad | hq (the offline double-precision "
      "blend).\n"
      "cache_dir: None = the default map cache, False = no cache, or a folder.\n"
      "incomplete: what a recording's frame set lacking cameras becomes, as `omma render --incomplete`:\n"
      "'hold' (each missing camera's last frame up to hold_max_age_ms old, 0 = two periods; else skipped),\n"
      "'skip', or 'fail' (RecordingError); never black cameras; a RuntimeWarning gives the counts.\n"
      "Returns a dict: outputs, width, height, seconds per stage, memory_bytes, incomplete (the counts).");

  m.def(
      "export_pto",
      [](const Rig& rig, const py::object& path, const py::object& frames_dir, int pano_width,
         int interpolator, bool linear_response) {
        if (pano_width < 8) throw py::value_error("pano_width must be at least 8");
        calib::PtoExportOptions opt;
        if (!frames_dir.is_none()) {
          const fs::path fd =
              py::str(py::module_::import("os").attr("fspath")(frames_dir)).cast<std::string>();
          if (path.is_none()) {
            opt.frames_dir = fd.string();
          } else {
            const fs::path p = py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
            opt.frames_dir = fs::relative(fs::absolute(fd), fs::absolute(p).parent_path()).string();
            if (opt.frames_dir.empty()) opt.frames_dir = fs::absolute(fd).string();
          }
        }
        opt.pano_width = pano_width;
        opt.interpolator = interpolator;
        opt.linear_response = linear_response;
        if (std::string why; !opt.IsValid(&why)) throw py::value_error(why);
        const calib::PtoExportSummary r = calib::export_pto(rig, opt);
        if (!path.is_none())
          write_text_atomically(py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>(),
                                r.text);
        py::dict d;
        d["text"] = r.text;
        d["lens_fit_max_px"] = r.max_fit_px;
        d["lens_fit_rms_px"] = r.rms_fit_px;
        d["warnings"] = r.warnings;
        return d;
      },
      py::arg("rig"), py::arg("path") = py::none(), py::arg("frames_dir") = py::none(),
      py::arg("pano_width") = 1440, py::arg("interpolator") = 0, py::arg("linear_response") = false,
      "The rig as a Hugin project (PanoTools conventions, calib/pto.h), as `omma pto export`; written\n"
      "atomically to `path` if given. frames_dir: images are DIR/cam_XX.png (relative to the project's\n"
      "folder). Returns a dict: text, lens_fit_max_px, lens_fit_rms_px, warnings.");
  m.def(
      "import_pto",
      [](const py::object& path, const py::object& text, const py::object& base_dir) {
        if (path.is_none() == text.is_none())
          throw py::value_error("import_pto: give path or text (one of them)");
        std::string t;
        fs::path base;
        if (!path.is_none()) {
          const fs::path p = py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
          t = read_text_file(p, kMaxTextFileBytes, "PTO file");
          base = p.parent_path();
        } else {
          t = text.cast<std::string>();
        }
        if (!base_dir.is_none())
          base = py::str(py::module_::import("os").attr("fspath")(base_dir)).cast<std::string>();
        calib::PtoImportSummary r;
        {
          py::gil_scoped_release release;
          r = calib::import_pto(t, base);
        }
        py::dict d;
        d["rig"] = r.rig;
        d["lens_fit_max_px"] = r.max_fit_px;
        d["warnings"] = r.warnings;
        return d;
      },
      py::arg("path") = py::none(), py::arg("text") = py::none(), py::arg("base_dir") = py::none(),
      "Reads a Hugin project (rectilinear f0 images only) into a rig, as `omma pto import`: from the file\n"
      "`path` or the string `text` (image names resolved in base_dir, default the file's folder). Returns\n"
      "a dict: rig (omma.Rig), lens_fit_max_px, warnings.");
}

}  // namespace omma::py
