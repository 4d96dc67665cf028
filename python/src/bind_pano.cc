// The reference stitcher, quality figures, images and frames folders, and calibration for Python.
#include <cmath>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "omma/calib/calibrate.h"
#include "omma/core/frames.h"
#include "omma/core/grid.h"
#include "omma/core/io.h"
#include "omma/io/metadata.h"
#include "omma/pano/maps.h"
#include "omma/pano/quality.h"
#include "omma/pano/refocus.h"
#include "omma/pano/stitch.h"

namespace omma::py {

namespace {

PanoGrid grid_from(const std::string& projection, const py::object& size) {
  const cv::Size s = size_from_python(size);
  return PanoGrid{parse_projection(projection), s.width, s.height};
}

py::object number_or_none(double x) {
  return std::isfinite(x) ? py::object(py::float_(x)) : py::object(py::none());
}

// An image argument for the quality functions (uint8, uint16 or float32; gray or BGR).
cv::Mat image_arg(const py::handle& a, const char* what) { return mat_from_array(a, what); }

cv::Mat mask_arg(const py::object& a, cv::Size size) {
  if (a.is_none()) return {};
  ImageSpec spec;
  spec.allow_u16 = spec.allow_f32 = false;
  cv::Mat m = mat_from_array(a, "mask", spec);
  if (m.channels() != 1) throw py::value_error("mask must be uint8 of shape (H, W): non-zero inside");
  if (m.size() != size)
    throw py::value_error(
        fmt::format("mask is {}x{}, the image {}x{}", m.cols, m.rows, size.width, size.height));
  return m;
}

}  // namespace

void add_pano(py::module_& m) {
  m.def(
      "stitch",
      [](const Rig& rig, const py::object& frames, const std::string& method, const std::string& projection,
         const py::object& size, bool progress) {
        pano::StitchOptions o;
        o.method = pano::parse_method(method);
        o.grid = grid_from(projection, size);
        o.progress = progress;
        std::vector<py::object> keep;
        const std::vector<cv::Mat> f = frames_from_python(frames, rig, {}, &keep);
        cv::Mat out;
        {
          py::gil_scoped_release release;
          out = pano::stitch(rig, f, o);
        }
        return array_from_mat(out);
      },
      py::arg("rig"), py::arg("frames"), py::arg("method") = "mrf", py::arg("projection") = "vr180",
      py::arg("size") = py::make_tuple(1080, 1080), py::arg("progress") = false,
      "The reference panorama (thesis §2.4.2, ch. 4), as `omma stitch`: float32 (H, W, 3) BGR in [0, 1].\n"
      "frames: one image per rig camera (list, or an (N, H, W, C) array), uint8/uint16/float32, BGR or "
      "gray.\n"
      "method: nn | linear | gaussian | mrf | mrf-spherical | sad; projection: vr180 | equirect | "
      "equirect-full.");
  m.def(
      "refocus",
      [](const Rig& rig, const py::object& frames, double focus_mm, const py::object& focus_depth,
         const py::object& aperture_mm, const std::string& shape, const std::string& combine,
         const std::string& projection, const py::object& size, bool progress) {
        pano::RefocusOptions o;
        o.grid = grid_from(projection, size);
        o.focus_mm = focus_mm;
        if (!focus_depth.is_none()) {
          // Millimetres (inf allowed: refocus checks the values), not an image in [0, 1].
          const auto d = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(focus_depth);
          if (!d || d.ndim() != 2) throw py::value_error("focus_depth must be a float (H, W) array of mm");
          o.focus_depth =
              cv::Mat(int(d.shape(0)), int(d.shape(1)), CV_32FC1, const_cast<float*>(d.data())).clone();
        }
        o.aperture_mm =
            aperture_mm.is_none() ? std::numeric_limits<double>::infinity() : aperture_mm.cast<double>();
        o.shape = pano::parse_aperture_shape(shape);
        o.combine = pano::parse_refocus_combine(combine);
        o.progress = progress;
        std::vector<py::object> keep;
        const std::vector<cv::Mat> f = frames_from_python(frames, rig, {}, &keep);
        pano::RefocusSummary r;
        {
          py::gil_scoped_release release;
          r = pano::refocus(rig, f, o);
        }
        return array_from_mat(r.image);
      },
      py::arg("rig"), py::arg("frames"), py::arg("focus_mm") = 1000.0, py::arg("focus_depth") = py::none(),
      py::arg("aperture_mm") = py::none(), py::arg("shape") = "gaussian", py::arg("combine") = "mean",
      py::arg("projection") = "vr180", py::arg("size") = py::make_tuple(1080, 1080),
      py::arg("progress") = false,
      "Synthetic-aperture refocusing, as `omma refocus`: float32 (H, W, 3) BGR in [0, 1].\n"
      "focus_mm: the focal sphere's distance from the rig centre (mm; inf allowed), or focus_depth: a "
      "float32 "
      "(H, W) depth map in mm (a focal surface).\n"
      "aperture_mm: the synthetic aperture's radius (a camera's weight exp(-r^2/2A^2), r its distance from "
      "the ray; None or inf = every camera alike, 0 = the nearest camera); shape: gaussian | box; combine: "
      "mean | "
      "median.");
  m.attr("METHODS") = [] {
    std::vector<std::string> names;
    for (auto meth : pano::all_methods()) names.push_back(pano::to_string(meth));
    return names;
  }();
  m.attr("PROJECTIONS") = std::vector<std::string>{"vr180", "equirect", "equirect-full"};

  m.def(
      "seam_mask",
      [](const Rig& rig, const std::string& projection, const py::object& size) {
        return array_from_mat(pano::seam_mask(pano::coverage_map(rig, grid_from(projection, size)), false));
      },
      py::arg("rig"), py::arg("projection") = "vr180", py::arg("size") = py::make_tuple(1080, 1080),
      "The seam band (directions seen by two or more cameras) as a uint8 (H, W) mask, 255 inside.");
  m.def(
      "coverage_map",
      [](const Rig& rig, const std::string& projection, const py::object& size) {
        return array_from_mat(pano::coverage_map(rig, grid_from(projection, size)));
      },
      py::arg("rig"), py::arg("projection") = "vr180", py::arg("size") = py::make_tuple(1080, 1080),
      "Number of cameras seeing each direction, uint8 (H, W).");
  m.def(
      "evaluate",
      [](const py::object& pano, const py::object& truth, const py::object& seam) {
        const cv::Mat p = image_arg(pano, "pano"), t = image_arg(truth, "truth");
        const pano::EvalSummary r = pano::evaluate(p, t, mask_arg(seam, p.size()));
        py::dict d;
        d["psnr_db"] = number_or_none(r.psnr_db);
        d["ssim"] = r.ssim;
        d["seam_psnr_db"] = seam.is_none() ? py::object(py::none()) : number_or_none(r.seam_psnr_db);
        return d;
      },
      py::arg("pano"), py::arg("truth"), py::arg("seam") = py::none(),
      "PSNR (dB), mean SSIM and the PSNR over the seam band (mask from seam_mask()), as `omma eval`.\n"
      "Images: uint8/uint16/float32 in [0, 1], compared at full scale. None where a figure is "
      "infinite/absent.");
  m.def(
      "psnr",
      [](const py::object& a, const py::object& b, const py::object& mask) {
        const cv::Mat x = image_arg(a, "a");
        return pano::psnr_db(x, image_arg(b, "b"), mask_arg(mask, x.size()));
      },
      py::arg("a"), py::arg("b"), py::arg("mask") = py::none(), "PSNR in dB (inf for identical images).");
  m.def(
      "ssim",
      [](const py::object& a, const py::object& b) {
        return pano::ssim(image_arg(a, "a"), image_arg(b, "b"));
      },
      py::arg("a"), py::arg("b"), "Mean SSIM (11x11 Gaussian window, sigma 1.5).");

  m.def(
      "to_u8",
      [](const py::object& a) {
        return array_from_mat(to_u8(mat_from_array(a, "image", {false, false, true, true, false})));
      },
      py::arg("image"), "float32 [0, 1] -> uint8 (rounded, saturated).");
  m.def(
      "read_image", [](const std::filesystem::path& path) { return array_from_mat(read_image(path)); },
      py::arg("path"),
      "Reads an image as stored (BGR, 8 or 16 bit); IoError naming the path if missing or unreadable.");
  m.def(
      "write_image",
      [](const std::filesystem::path& path, const py::object& image, const py::object& projection) {
        ImageSpec spec;
        spec.allow_f32 = false;
        spec.allow_bgra = true;
        const cv::Mat m = mat_from_array(image, "image", spec);
        if (projection.is_none()) return write_image(path, m);
        io::write_panorama(path, m,
                           PanoGrid{parse_projection(projection.cast<std::string>()), m.cols, m.rows});
      },
      py::arg("path"), py::arg("image"), py::arg("projection") = py::none(),
      "Writes an image atomically (format from the extension). With a projection (vr180, equirect,\n"
      "equirect-full) a JPEG or PNG panorama carries the 360-degree GPano XMP (omma/io/metadata.h).");
  m.def(
      "add_spherical_video_metadata",
      [](const std::filesystem::path& path, const std::string& projection, const py::object& size) {
        io::add_spherical_video_metadata(path, grid_from(projection, size));
      },
      py::arg("path"), py::arg("projection"), py::arg("size"),
      "Adds Spherical Video V2 metadata (st3d, sv3d) for a panorama video of this projection and size\n"
      "(width, height) to an MP4 file, rewritten atomically (as `omma run` does for its .mp4 sinks).");
  m.def(
      "load_frames",
      [](const std::filesystem::path& dir, const Rig& rig) {
        py::list out;
        for (auto& f : load_frames(dir, rig)) out.append(array_from_mat(f));
        return out;
      },
      py::arg("dir"), py::arg("rig"),
      "The frames folder's DIR/cam_XX.png of every camera of the rig, in rig order.");

  using calib::CalibrationOptions;
  py::class_<CalibrationOptions>(
      m, "CalibrationOptions",
      "Options of calibrate() (omma/calib/calibrate.h); calibrate() takes these fields as "
      "keyword arguments.")
      .def(py::init<>())
      .def_property(
          "scene", [](const CalibrationOptions& o) { return calib::to_string(o.scene); },
          [](CalibrationOptions& o, const std::string& s) { o.scene = calib::parse_scene_model(s); })
      .def_readwrite("estimate_rotation", &CalibrationOptions::estimate_rotation)
      .def_readwrite("estimate_focal", &CalibrationOptions::estimate_focal)
      .def_readwrite("estimate_center", &CalibrationOptions::estimate_center)
      .def_readwrite("radial_terms", &CalibrationOptions::radial_terms)
      .def_readwrite("estimate_tangential", &CalibrationOptions::estimate_tangential)
      .def_readwrite("share_focal", &CalibrationOptions::share_focal)
      .def_readwrite("share_center", &CalibrationOptions::share_center)
      .def_readwrite("share_distortion", &CalibrationOptions::share_distortion)
      .def_readwrite("loss", &CalibrationOptions::loss)
      .def_readwrite("loss_scale_px", &CalibrationOptions::loss_scale_px)
      .def_readwrite("outlier_px", &CalibrationOptions::outlier_px)
      .def_readwrite("prior_rotation_deg", &CalibrationOptions::prior_rotation_deg)
      .def_readwrite("prior_mean_focal", &CalibrationOptions::prior_mean_focal)
      .def_readwrite("refine_rounds", &CalibrationOptions::refine_rounds)
      .def_readwrite("dense_refine", &CalibrationOptions::dense_refine)
      .def_readwrite("max_iterations", &CalibrationOptions::max_iterations)
      .def_readwrite("min_observations", &CalibrationOptions::min_observations)
      .def_readwrite("threads", &CalibrationOptions::threads)
      .def_property(
          "upsample", [](const CalibrationOptions& o) { return o.features.upsample; },
          [](CalibrationOptions& o, int v) { o.features.upsample = v; },
          "SIFT on frames upsampled this much (1 = off)")
      .def_property(
          "max_features", [](const CalibrationOptions& o) { return o.features.max_features; },
          [](CalibrationOptions& o, int v) { o.features.max_features = v; }, "SIFT features per camera");

  m.def(
      "calibrate",
      [](const Rig& rig, const py::object& frames, const py::kwargs& kwargs) {
        CalibrationOptions o;
        set_fields(py::cast(&o, py::return_value_policy::reference), kwargs, "calibrate");
        std::vector<py::object> keep;
        const std::vector<cv::Mat> f = frames_from_python(frames, rig, {}, &keep);
        calib::CalibrationSummary r;
        {
          py::gil_scoped_release release;
          r = calib::calibrate_rig(rig, f, o);
        }
        py::dict d;
        d["rig"] = r.rig;
        d["scene"] = calib::to_string(r.scene);
        d["rms_px"] = r.rms_px;
        d["initial_rms_px"] = r.initial_rms_px;
        d["matches"] = r.matches;
        d["inliers"] = r.inliers;
        d["pairs"] = r.pairs;
        d["tracks"] = r.tracks;
        d["observations"] = r.observations;
        d["rejected"] = r.rejected;
        d["uncalibrated_ids"] = r.uncalibrated_ids;
        d["warnings"] = r.warnings;
        py::list per;
        for (const auto& c : r.per_camera) {
          py::dict pc;
          pc["id"] = c.id;
          pc["rms_px"] = c.rms_px;
          pc["matches"] = c.matches;
          pc["calibrated"] = c.calibrated;
          per.append(pc);
        }
        d["per_camera"] = per;
        return d;
      },
      py::arg("rig"), py::arg("frames"),
      "Calibrates `rig` from one set of frames (thesis §3.6, as `omma calibrate`): SIFT, matching, RANSAC, "
      "Ceres\n"
      "bundle adjustment. Keyword arguments set CalibrationOptions fields (scene='far'|'near'|'auto', "
      "threads,\n"
      "estimate_focal, share_focal, radial_terms, ...). Returns a dict: 'rig' (the calibrated Rig), "
      "'rms_px',\n"
      "'initial_rms_px', counts, 'per_camera', 'warnings'.");
}

}  // namespace omma::py
