#include "arrays.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "omma/core/grid.h"
#include "omma/core/limits.h"

namespace omma::py {

namespace {

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string dtype_text(const py::array& a) { return py::str(a.dtype()).cast<std::string>(); }

}  // namespace

cv::Mat mat_from_array(const py::handle& obj, const std::string& what, const ImageSpec& spec) {
  if (!py::isinstance<py::array>(obj))
    throw py::type_error(fmt::format("{} must be a numpy.ndarray, got {}", what,
                                     py::str(obj.get_type().attr("__name__")).cast<std::string>()));
  const auto a = py::reinterpret_borrow<py::array>(obj);
  std::string allowed;
  auto allow = [&](bool on, const char* name) {
    if (on) allowed += (allowed.empty() ? "" : ", ") + std::string(name);
  };
  allow(spec.allow_u8, "uint8");
  allow(spec.allow_u16, "uint16");
  allow(spec.allow_f32, "float32 in [0, 1]");
  int depth = -1;
  if (spec.allow_u8 && a.dtype().is(py::dtype::of<uint8_t>()))
    depth = CV_8U;
  else if (spec.allow_u16 && a.dtype().is(py::dtype::of<uint16_t>()))
    depth = CV_16U;
  else if (spec.allow_f32 && a.dtype().is(py::dtype::of<float>()))
    depth = CV_32F;
  if (depth < 0)
    throw py::type_error(fmt::format("{} has dtype {}; expected {}", what, dtype_text(a), allowed));
  const int channels = a.ndim() == 2 ? 1 : a.ndim() == 3 ? int(a.shape(2)) : 0;
  const bool ok_channels =
      channels == 3 || (channels == 1 && spec.allow_gray) || (channels == 4 && spec.allow_bgra);
  if (!ok_channels)
    throw py::value_error(fmt::format("{} has shape {}; expected (H, W, 3){}{}", what, shape_text(a),
                                      spec.allow_gray ? ", (H, W, 1) or (H, W)" : "",
                                      spec.allow_bgra ? " or (H, W, 4)" : ""));
  const py::ssize_t rows = a.shape(0), cols = a.shape(1), item = a.itemsize();
  if (rows <= 0 || cols <= 0)
    throw py::value_error(fmt::format("{} is empty: shape {}", what, shape_text(a)));
  const py::ssize_t ch_stride = a.ndim() == 3 ? a.strides(2) : item;
  const py::ssize_t row_stride = a.strides(0);
  // Pixels side by side within a row, rows at a positive stride that holds a whole row.
  const bool in_place = ch_stride == item && a.strides(1) == item * channels &&
                        (rows == 1 || (row_stride >= cols * channels * item && row_stride % item == 0));
  if (!in_place)
    throw py::value_error(fmt::format(
        "{} (shape {}, strides {}) is not contiguous within its rows; pass numpy.ascontiguousarray({})", what,
        shape_text(a), py::str(a.attr("strides")).cast<std::string>(), what));
  const size_t step = rows == 1 ? size_t(cols * channels * item) : size_t(row_stride);
  // cv::Mat never writes through this view in the bindings (inputs are const); the cast only
  // satisfies its constructor.
  cv::Mat m(int(rows), int(cols), CV_MAKETYPE(depth, channels), const_cast<void*>(a.data()), step);
  if (depth == CV_32F) check_float_range(m, what);
  return m;
}

void check_float_range(const cv::Mat& m, const std::string& what) {
  int64_t not_finite = 0, below = 0, above = 0;
  float lo = 0, hi = 1;
  const int n = m.cols * m.channels();
  for (int y = 0; y < m.rows; ++y) {
    const float* p = m.ptr<float>(y);
    for (int i = 0; i < n; ++i) {
      const float v = p[i];
      if (v >= 0.f && v <= 1.f) continue;  // the common case; NaN fails both comparisons
      if (!std::isfinite(v)) {
        ++not_finite;
      } else if (v < 0.f) {
        ++below;
        lo = std::min(lo, v);
      } else {
        ++above;
        hi = std::max(hi, v);
      }
    }
  }
  const int64_t total = int64_t(m.rows) * n;
  if (not_finite > 0)
    throw py::value_error(
        fmt::format("{} holds {} NaN or infinite value(s) of {}: float32 images must hold "
                    "finite values in [0, 1] (e.g. numpy.nan_to_num)",
                    what, not_finite, total));
  if (below + above > 0) {
    const std::string msg = fmt::format(
        "{}: {} of {} float32 values outside [0, 1] ({} below 0, min {:g}; {} above 1, max {:g}) are "
        "clipped to [0, 1]",
        what, below + above, total, below, lo, above, hi);
    if (PyErr_WarnEx(PyExc_RuntimeWarning, msg.c_str(), 2) < 0) throw py::error_already_set();
  }
}

py::object array_from_mat(cv::Mat m) {
  if (m.empty()) return py::none();
  const int ch = m.channels();
  const size_t elem1 = m.elemSize1();
  py::dtype dt = m.depth() == CV_8U    ? py::dtype::of<uint8_t>()
                 : m.depth() == CV_16U ? py::dtype::of<uint16_t>()
                 : m.depth() == CV_32F ? py::dtype::of<float>()
                 : m.depth() == CV_64F ? py::dtype::of<double>()
                 : m.depth() == CV_32S ? py::dtype::of<int32_t>()
                                       : throw std::logic_error("array_from_mat: unsupported depth");
  std::vector<py::ssize_t> shape{m.rows, m.cols}, strides{py::ssize_t(m.step[0]), py::ssize_t(m.elemSize())};
  if (ch > 1) {
    shape.push_back(ch);
    strides.push_back(py::ssize_t(elem1));
  }
  auto* owner = new cv::Mat(std::move(m));  // shares the buffer's reference count
  py::capsule keep(owner, [](void* p) { delete static_cast<cv::Mat*>(p); });
  return py::array(dt, shape, strides, owner->data, keep);
}

std::vector<cv::Mat> frames_from_python(const py::handle& frames, const Rig& rig, const ImageSpec& spec,
                                        std::vector<py::object>* keep) {
  const size_t n = rig.cameras.size();
  std::vector<py::object> items;
  if (py::isinstance<py::array>(frames)) {
    const auto a = py::reinterpret_borrow<py::array>(frames);
    if (a.ndim() != 3 && a.ndim() != 4)
      throw py::value_error(
          fmt::format("frames has shape {}; expected (N, H, W, C) or (N, H, W), or a list of "
                      "(H, W, C) arrays, one per camera",
                      shape_text(a)));
    for (py::ssize_t i = 0; i < a.shape(0); ++i) items.push_back(a[py::int_(i)]);
  } else if (py::isinstance<py::list>(frames) || py::isinstance<py::tuple>(frames)) {
    for (const auto& f : frames) items.push_back(py::reinterpret_borrow<py::object>(f));
  } else {
    throw py::type_error(
        fmt::format("frames must be a list of numpy arrays (one per camera) or one array of "
                    "shape (N, H, W, C), got {}",
                    py::str(frames.get_type().attr("__name__")).cast<std::string>()));
  }
  if (items.size() != n)
    throw py::value_error(
        fmt::format("expected {} frames (one per rig camera, in rig order), got {}", n, items.size()));
  std::vector<cv::Mat> out;
  out.reserve(n);
  for (size_t c = 0; c < n; ++c) {
    cv::Mat m = mat_from_array(items[c], fmt::format("frames[{}]", c), spec);
    const auto& in = rig.cameras[c].in;
    if (m.cols != in.width || m.rows != in.height)
      throw py::value_error(fmt::format("frames[{}] is {}x{} (W x H) but camera id {} is {}x{}", c, m.cols,
                                        m.rows, rig.cameras[c].id, in.width, in.height));
    out.push_back(m);
  }
  if (keep) *keep = std::move(items);
  return out;
}

cv::Size size_from_python(const py::handle& size, const std::string& what) {
  if (py::isinstance<py::str>(size)) {
    const Size2 s = parse_size(size.cast<std::string>());
    return {s.width, s.height};
  }
  if (py::isinstance<py::sequence>(size) && py::len(size) == 2) {
    try {
      const auto t = size.cast<std::pair<int64_t, int64_t>>();
      if (t.first > 0 && t.second > 0) {
        check_image_size(t.first, t.second, what);  // the limits of core/limits.h, as "WxH" has
        return {int(t.first), int(t.second)};
      }
    } catch (const py::cast_error&) {
    }
  }
  throw py::value_error(fmt::format("{} must be (width, height) with positive integers or \"WxH\", got {}",
                                    what, py::repr(size).cast<std::string>()));
}

}  // namespace omma::py
