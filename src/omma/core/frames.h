// The camera-frames folder: the contract between the simulator, the ISP, the stitcher, the
// calibrator and the engine's image-sequence sources.
//
//   DIR/cam_00.png, cam_01.png, ...   one RGB image per camera, named by camera id (2+ digits),
//                                     8- or 16-bit, size = the camera's intrinsics width x height
//                                     (each camera its own size); also cam_00.jpg / .jpeg / .tif /
//                                     .tiff (any case), e.g. a real camera's JPEGs; formats may mix
//                                     across cameras, but a camera with two files (cam_00.png AND
//                                     cam_00.jpg) is an error naming both. Gray images become 3
//                                     channels; a JPEG's EXIF orientation is applied (the size
//                                     compared with the rig is the size as displayed, rotated)
//   DIR/cam_00_raw.png, ...           optional: 16-bit single-channel RGGB Bayer, 10-bit values
//   DIR/truth.png                     optional: the ideal panorama (simulator ground truth)
//   DIR/rig.json, DIR/rig_true.json   optional: nominal rig, and the true (perturbed) rig
//
// Shots of a static scene (`omma simulate --shots N`, calibration): a folder of frames folders
// DIR/shot_00, DIR/shot_01, ... (any folder names "shot_*", taken in name order).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omma/core/rig.h"

namespace omma {

std::string frame_filename(int camera_id);      // "cam_07.png"
std::string raw_frame_filename(int camera_id);  // "cam_07_raw.png"
// The extensions a camera frame may have, in lower case: ".png", ".jpg", ".jpeg", ".tif", ".tiff".
const std::vector<std::string>& frame_extensions();
// Is `name` (a file name, no folder) a camera frame's: cam_<digits> with one of frame_extensions()
// (any case)? cam_07_raw.png is not.
bool is_frame_filename(const std::string& name);
// DIR/cam_XX.<ext> of camera `camera_id`: the one file among frame_extensions() that exists.
// Throws IoError if none does (naming DIR/cam_XX.png and the extensions tried) or if several do
// (naming them: which one is meant cannot be guessed).
std::filesystem::path find_frame(const std::filesystem::path& dir, int camera_id);

// Loads DIR/cam_XX.png (or .jpg ..., find_frame) for every camera of `rig`, in rig order, as stored
// (8U or 16U, 3 channels; gray images are expanded to 3 channels, an alpha channel dropped; EXIF
// orientation applied). Throws IoError naming the file if one is missing, ambiguous, unreadable, or
// not the size the rig says (both sizes named).
std::vector<cv::Mat> load_frames(const std::filesystem::path& dir, const Rig& rig);
// Same for the raw Bayer frames (CV_16UC1).
std::vector<cv::Mat> load_raw_frames(const std::filesystem::path& dir, const Rig& rig);

// The frames folders that `paths` name: each path is a frames folder (it holds a camera frame,
// is_frame_filename), or a
// shots folder (its shot_* sub-folders, in name order). Throws IoError if a path does not exist or
// is neither.
std::vector<std::filesystem::path> expand_shot_folders(const std::vector<std::filesystem::path>& paths);
// load_frames of every folder of expand_shot_folders(paths): one frame set per shot.
std::vector<std::vector<cv::Mat>> load_frame_sets(const std::vector<std::filesystem::path>& paths,
                                                  const Rig& rig);

// 8U / 16U / 32F image -> CV_32F with the same channels, values in [0, 1].
cv::Mat to_float01(const cv::Mat& image);
// CV_32F [0, 1] -> CV_8U (rounded, saturated).
cv::Mat to_u8(const cv::Mat& image01);

}  // namespace omma
