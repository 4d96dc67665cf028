// NumPy arrays <-> cv::Mat for the Python bindings, without copies where the layout allows.
//
// In: an image is a numpy.ndarray of dtype uint8, uint16 or float32 (float32: finite values in [0, 1],
// checked: check_float_range) and
// shape (H, W) or (H, W, C) with C = 1 or 3 (BGR, as OpenCV's cv2 reads images), C = 4 (BGRA)
// where a function says so. Its pixels must be contiguous within each row (the channels of a pixel
// and the pixels of a row side by side, rows at any positive stride), so C-contiguous arrays and
// their row/column crops (a[10:200, 20:300]) are used in place; anything else (a[:, ::2],
// transposed or Fortran-ordered arrays, negative strides) raises ValueError naming the array and
// saying how to fix it (numpy.ascontiguousarray). Other dtypes or shapes raise TypeError/ValueError.
// Out: a cv::Mat becomes an ndarray that owns the Mat's buffer (no copy): (H, W, C), or (H, W)
// for one channel; None for an empty Mat.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "omma/core/rig.h"

namespace omma::py {

namespace py = pybind11;

struct ImageSpec {
  bool allow_u8 = true, allow_u16 = true, allow_f32 = true;
  bool allow_gray = true, allow_bgra = false;
};

// float32 images: values must be finite (NaN or inf raises ValueError with their count) and lie in
// [0, 1]: values outside are clipped where they are used, so they raise a RuntimeWarning (Python's
// warnings module: an error under `-W error`) with their count, minimum and maximum.
void check_float_range(const cv::Mat& m, const std::string& what);

// A view of `obj` (no copy). `what` names the argument in messages ("frames[3]", "truth").
// The returned Mat points into the array's memory: keep `obj` alive while it is used.
cv::Mat mat_from_array(const py::handle& obj, const std::string& what, const ImageSpec& spec = {});

// The ndarray owning `m` (its reference count keeps the pixels alive; no copy).
py::object array_from_mat(cv::Mat m);

// A frames argument: a sequence of images (list or tuple) or one array of shape (N, H, W[, C]),
// one image per rig camera in rig order. Checks the count against the rig and every frame's size
// (ValueError naming the frame and the camera id). `keep` receives the arrays the views point
// into, so that they stay alive while the GIL is released.
std::vector<cv::Mat> frames_from_python(const py::handle& frames, const Rig& rig, const ImageSpec& spec,
                                        std::vector<py::object>* keep);

// (width, height) from a "WxH" string or a (width, height) tuple.
cv::Size size_from_python(const py::handle& size, const std::string& what = "size");

}  // namespace omma::py
