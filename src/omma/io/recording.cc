#include "omma/io/recording.h"

#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <limits>
#include <mutex>
#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <hdf5.h>
#include <opencv2/imgproc.hpp>

#include "omma/core/frames.h"
#include "omma/core/io.h"
#include "omma/core/limits.h"
#include "omma/core/parse.h"
#include "omma/core/valid.h"
#include "omma/core/version.h"

namespace omma::io {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// The serial HDF5 library is not thread-safe: every call goes through this lock.
std::mutex& h5_mutex() {
  static std::mutex m;
  return m;
}

void quiet_hdf5() {
  static std::once_flag once;
  std::call_once(once, [] { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); });
}

// Closes an HDF5 id of any kind when it goes out of scope.
struct Hid {
  hid_t id = -1;
  Hid() = default;
  explicit Hid(hid_t i) : id(i) {}
  Hid(const Hid&) = delete;
  Hid& operator=(const Hid&) = delete;
  Hid(Hid&& o) noexcept : id(o.id) { o.id = -1; }
  Hid& operator=(Hid&& o) noexcept {
    std::swap(id, o.id);
    return *this;
  }
  ~Hid() { reset(); }
  void reset() {
    if (id >= 0) {
      switch (H5Iget_type(id)) {
        case H5I_FILE:
          H5Fclose(id);
          break;
        case H5I_DATASET:
          H5Dclose(id);
          break;
        case H5I_DATASPACE:
          H5Sclose(id);
          break;
        case H5I_GENPROP_LST:
          H5Pclose(id);
          break;
        case H5I_ATTR:
          H5Aclose(id);
          break;
        case H5I_DATATYPE:
          H5Tclose(id);
          break;
        default:
          break;
      }
    }
    id = -1;
  }
  operator hid_t() const { return id; }
  bool ok() const { return id >= 0; }
};

void write_int_attr(hid_t obj, const char* name, int64_t v) {
  Hid space(H5Screate(H5S_SCALAR));
  Hid a(H5Acreate2(obj, name, H5T_NATIVE_INT64, space, H5P_DEFAULT, H5P_DEFAULT));
  H5Awrite(a, H5T_NATIVE_INT64, &v);
}

void write_double_attr(hid_t obj, const char* name, double v) {
  Hid space(H5Screate(H5S_SCALAR));
  Hid a(H5Acreate2(obj, name, H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT));
  H5Awrite(a, H5T_NATIVE_DOUBLE, &v);
}

// A scalar variable-length UTF-8 string attribute (h5py reads it as str, h5dump prints it).
void write_string_attr(hid_t obj, const char* name, const std::string& v) {
  Hid type(H5Tcopy(H5T_C_S1));
  H5Tset_size(type, H5T_VARIABLE);
  H5Tset_cset(type, H5T_CSET_UTF8);
  Hid space(H5Screate(H5S_SCALAR));
  Hid a(H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT));
  const char* p = v.c_str();
  H5Awrite(a, type, &p);
}

template <typename T>
void write_array_attr(hid_t obj, const char* name, hid_t type, const std::vector<T>& v) {
  const hsize_t n = v.size();
  Hid space(H5Screate_simple(1, &n, nullptr));
  Hid a(H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT));
  H5Awrite(a, type, v.data());
}

// "2026-12-03T18:26:04.123456789Z" for ns since the Unix epoch (ISO 8601, UTC).
std::string iso8601_utc(int64_t unix_ns) {
  const time_t secs = time_t(unix_ns / 1'000'000'000);
  struct tm tm {};
  gmtime_r(&secs, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  return fmt::format("{}.{:09d}Z", buf, unix_ns % 1'000'000'000);
}

constexpr const char* kTimeBase =
    "steady clock (CLOCK_MONOTONIC) of the recording machine, ns since the recording's start; "
    "start_unix_ns is the system clock (UTC) at that start";

std::string stream_name(int camera_id) { return fmt::format("cam_{:02d}.h5", camera_id); }

// Bytes that may still be written to `file` in `dir`: the free space of its file system, and the
// process's file-size limit (RLIMIT_FSIZE) minus the file's size. HDF5 cannot undo a write that
// fails half-way (its end-of-allocation would point past the end of the file, which readers refuse
// as truncated), so the writer stops BEFORE the space runs out.
uint64_t writable_bytes(const fs::path& dir, uint64_t file_size) {
  uint64_t left = UINT64_MAX;
  struct statvfs sv {};
  if (statvfs(dir.c_str(), &sv) == 0) left = uint64_t(sv.f_bavail) * sv.f_frsize;
  struct rlimit rl {};
  if (getrlimit(RLIMIT_FSIZE, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY)
    left = std::min<uint64_t>(left, rl.rlim_cur > file_size ? rl.rlim_cur - file_size : 0);
  return left;
}

}  // namespace

// ---- manifest ------------------------------------------------------------------------------

bool valid_recording_fps(double fps, std::string* why) {
  if (!(fps >= kMinRecordingFps && fps <= kMaxRecordingFps))
    return invalid(
        why, fmt::format("fps must be in [{:g}, {:g}], got {}", kMinRecordingFps, kMaxRecordingFps, fps));
  return true;
}

bool valid_recording_clock_mhz(double mhz, std::string* why) {
  if (!(mhz >= 0 && mhz <= kMaxRecordingClockMhz))
    return invalid(why, fmt::format("clock must be in [0, {:g}] MHz (0 = not given), got {}",
                                    kMaxRecordingClockMhz, mhz));
  return true;
}

bool valid_recording_bits(int64_t bits, std::string* why) {
  if (bits < kMinRecordingBits || bits > kMaxRecordingBits)
    return invalid(why,
                   fmt::format("bits must be {}..{}, got {}", kMinRecordingBits, kMaxRecordingBits, bits));
  return true;
}

namespace {
// Does `text` hold an ASCII control character (below 0x20, or DEL; NUL included)?
bool has_control_char(const std::string& text) {
  return std::any_of(text.begin(), text.end(),
                     [](char ch) { return static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f; });
}
}  // namespace

bool valid_sensor_mode(const std::string& mode, std::string* why) {
  if (mode.size() > kMaxSensorModeBytes)
    return invalid(why, fmt::format("sensor mode must be at most {} bytes", kMaxSensorModeBytes));
  if (has_control_char(mode)) return invalid(why, "sensor mode must not hold control characters");
  return true;
}

bool valid_start_unix_ns(int64_t ns, std::string* why) {
  if (ns < 0) return invalid(why, fmt::format("start_unix_ns must be >= 0, got {}", ns));
  return true;
}

bool valid_stream_file_name(const std::string& name, std::string* why) {
  if (name.empty() || name.size() > kMaxStreamNameBytes)
    return invalid(why, fmt::format("stream file names must have 1..{} bytes", kMaxStreamNameBytes));
  if (name.find('/') != std::string::npos || name.find("..") != std::string::npos || name == ".")
    return invalid(why, fmt::format("stream file name '{}' is not a plain name in the folder", name));
  if (has_control_char(name))
    return invalid(why, "stream file names must not hold control characters (NUL included)");
  return true;
}

bool RecordingManifest::IsValid(std::string* why) const {
  try {
    rig.validate();
  } catch (const RigError& e) {
    return invalid(why, std::string("rig: ") + e.what());
  } catch (const std::invalid_argument& e) {
    return invalid(why, std::string("rig: ") + e.what());
  }
  if (!valid_sensor_mode(sensor_mode, why) || !valid_recording_clock_mhz(clock_mhz, why) ||
      !valid_recording_fps(fps, why) || !valid_recording_bits(bits, why) ||
      !valid_start_unix_ns(start_unix_ns, why))
    return false;
  if (files.size() != rig.cameras.size())
    return invalid(why,
                   fmt::format("{} stream files for a rig of {} cameras", files.size(), rig.cameras.size()));
  std::vector<std::string> sorted = files;
  for (const std::string& f : files)
    if (!valid_stream_file_name(f, why)) return false;
  std::sort(sorted.begin(), sorted.end());
  if (const auto d = std::adjacent_find(sorted.begin(), sorted.end()); d != sorted.end())
    return invalid(why, fmt::format("stream file '{}' is named twice", *d));
  if (!camera_fps.empty() && camera_fps.size() != rig.cameras.size())
    return invalid(
        why, fmt::format("{} camera rates for a rig of {} cameras", camera_fps.size(), rig.cameras.size()));
  for (const double f : camera_fps)
    if (f != 0 && !valid_recording_fps(f, why)) return false;
  if (!(exposure_s >= 0 && exposure_s <= kMaxExposureS))
    return invalid(why, fmt::format("exposure must be in [0, {:g}] s (0 = not known), got {}", kMaxExposureS,
                                    exposure_s));
  return true;
}

json RecordingManifest::to_json() const {
  json streams = json::array();
  for (size_t c = 0; c < files.size(); ++c) {
    json st = {{"camera", rig.cameras[c].id},
               {"file", files[c]},
               {"width", rig.cameras[c].in.width},
               {"height", rig.cameras[c].in.height}};
    if (c < camera_fps.size()) st["fps"] = camera_fps[c];
    if (exposure_s > 0) st["exposure_s"] = exposure_s;
    streams.push_back(st);
  }
  return {{"format", "omma-recording"},
          {"version", 1},
          {"container", "hdf5"},
          {"rig", rig_to_json(rig)},
          {"sensor_mode", sensor_mode},
          {"clock_mhz", clock_mhz},
          {"fps", fps},
          {"bits", bits},
          {"bayer", "RGGB"},
          {"start_unix_ns", start_unix_ns},
          {"complete", complete},
          {"streams", streams}};
}

namespace {

// Strict readers of manifest fields: the JSON type first, then the range, before any narrowing.
// `where` is "" for the top level or "stream I ". Values are shown cut to 40 characters.
std::string shown(const json& v) {
  std::string s = v.dump();
  if (s.size() > 40) s = s.substr(0, 37) + "...";
  return s;
}

const json& manifest_field(const json& obj, const std::string& key, const std::string& where = "") {
  const auto it = obj.find(key);
  if (it == obj.end()) throw RecordingError(fmt::format("manifest: {}lacks '{}'", where, key));
  return *it;
}

// A JSON integer (not a float, not a boolean; beyond 64 bits nlohmann holds a float) in [lo, hi].
int64_t manifest_int(const json& v, const std::string& key, int64_t lo, int64_t hi,
                     const std::string& where = "") {
  if (!v.is_number_integer())
    throw RecordingError(fmt::format("manifest: {}'{}' must be an integer, got {}", where, key, shown(v)));
  const std::optional<int64_t> i = json_integer(v, lo, hi);  // core/parse.h
  if (!i)
    throw RecordingError(
        fmt::format("manifest: {}'{}' = {} is out of range ({}..{})", where, key, shown(v), lo, hi));
  return *i;
}

double manifest_number(const json& v, const std::string& key) {
  if (!v.is_number())
    throw RecordingError(fmt::format("manifest: '{}' must be a number, got {}", key, shown(v)));
  const double d = v.get<double>();
  if (!std::isfinite(d)) throw RecordingError(fmt::format("manifest: '{}' is not finite", key));
  return d;
}

std::string manifest_string(const json& v, const std::string& key, const std::string& where = "") {
  if (!v.is_string())
    throw RecordingError(fmt::format("manifest: {}'{}' must be a string, got {}", where, key, shown(v)));
  return v.get<std::string>();
}

// A field checked by one of the validators: its reason as a RecordingError.
void check_field(bool ok, const std::string& why) {
  if (!ok) throw RecordingError("manifest: " + why);
}

}  // namespace

RecordingManifest RecordingManifest::from_json(const json& j) {
  try {
    if (!j.is_object() || !j.contains("format") || j["format"] != "omma-recording")
      throw RecordingError("not an omma recording manifest (format is not 'omma-recording')");
    const int64_t version = manifest_int(manifest_field(j, "version"), "version", INT64_MIN, INT64_MAX);
    if (version != 1) throw RecordingError(fmt::format("unsupported recording version {}", version));
    if (j.contains("container") && j["container"] != "hdf5")
      throw RecordingError("manifest: 'container' must be \"hdf5\", got " + shown(j["container"]));
    if (j.contains("bayer") && j["bayer"] != "RGGB")
      throw RecordingError("manifest: 'bayer' must be \"RGGB\", got " + shown(j["bayer"]));
    RecordingManifest m;
    std::string why;
    m.rig = rig_from_json(manifest_field(j, "rig"));
    if (j.contains("sensor_mode")) {
      m.sensor_mode = manifest_string(j["sensor_mode"], "sensor_mode");
      check_field(valid_sensor_mode(m.sensor_mode, &why), why);
    }
    if (j.contains("clock_mhz")) {
      m.clock_mhz = manifest_number(j["clock_mhz"], "clock_mhz");
      check_field(valid_recording_clock_mhz(m.clock_mhz, &why), why);
    }
    m.fps = manifest_number(manifest_field(j, "fps"), "fps");
    check_field(valid_recording_fps(m.fps, &why), why);
    m.bits = int(manifest_int(manifest_field(j, "bits"), "bits", kMinRecordingBits, kMaxRecordingBits));
    if (j.contains("start_unix_ns"))
      m.start_unix_ns = manifest_int(j["start_unix_ns"], "start_unix_ns", 0, INT64_MAX);
    if (j.contains("complete")) {
      if (!j["complete"].is_boolean())
        throw RecordingError("manifest: 'complete' must be true or false, got " + shown(j["complete"]));
      m.complete = j["complete"].get<bool>();
    }
    const json& streams = manifest_field(j, "streams");
    if (!streams.is_array() || streams.size() != m.rig.cameras.size())
      throw RecordingError(fmt::format("manifest: {} streams for a rig of {} cameras",
                                       streams.is_array() ? streams.size() : 0, m.rig.cameras.size()));
    for (size_t c = 0; c < streams.size(); ++c) {
      const json& s = streams[c];
      const RigCamera& cam = m.rig.cameras[c];
      const std::string where = fmt::format("stream {} ", c);
      if (!s.is_object()) throw RecordingError(fmt::format("manifest: {}must be an object", where));
      const int64_t id = manifest_int(manifest_field(s, "camera", where), "camera", 0, INT32_MAX, where);
      if (id != cam.id)
        throw RecordingError(
            fmt::format("manifest: {}is of camera {}, but camera {} of the rig is {}", where, id, c, cam.id));
      const std::string f = manifest_string(manifest_field(s, "file", where), "file", where);
      check_field(valid_stream_file_name(f, &why), why);
      const int64_t w = manifest_int(manifest_field(s, "width", where), "width", 1, kMaxImageSide, where);
      const int64_t h = manifest_int(manifest_field(s, "height", where), "height", 1, kMaxImageSide, where);
      if (w != cam.in.width || h != cam.in.height)
        throw RecordingError(
            fmt::format("manifest: stream {} is {}x{} but camera {} is {}x{} (mismatched sensor mode)", f, w,
                        h, cam.id, cam.in.width, cam.in.height));
      m.files.push_back(f);
      // Optional (streams written before them lack them): the camera's own rate, the exposure.
      if (s.contains("fps")) {
        const double f_c = manifest_number(s["fps"], where + "fps");
        if (f_c != 0) check_field(valid_recording_fps(f_c, &why), where + why);
        m.camera_fps.resize(streams.size(), 0);
        m.camera_fps[c] = f_c;
      }
      if (s.contains("exposure_s")) {
        const double e = manifest_number(s["exposure_s"], where + "exposure_s");
        if (!(e > 0 && e <= kMaxExposureS))
          throw RecordingError(fmt::format("manifest: {}'exposure_s' must be in (0, {:g}] s, got {}", where,
                                           kMaxExposureS, e));
        m.exposure_s = e;
      }
    }
    if (!m.IsValid(&why)) throw RecordingError("manifest: " + why);
    return m;
  } catch (const json::exception& e) {
    throw RecordingError(std::string("manifest: ") + e.what());
  } catch (const RigError& e) {
    throw RecordingError(std::string("manifest rig: ") + e.what());
  }
}

// ---- raw conversion ------------------------------------------------------------------------

cv::Mat to_raw_mosaic(const cv::Mat& frame, int bits) {
  if (bits < 8 || bits > 16) throw std::invalid_argument("raw bits must be 8..16");
  const int top = (1 << bits) - 1;
  if (frame.channels() == 1 && frame.depth() == CV_16U) {
    double mx = 0;
    cv::minMaxLoc(frame, nullptr, &mx);
    if (mx > top)
      throw std::invalid_argument(fmt::format("raw frame value {} does not fit {} bits", mx, bits));
    return frame.clone();
  }
  cv::Mat bgr;
  if (frame.channels() == 3)
    bgr = frame;
  else if (frame.channels() == 4)
    cv::cvtColor(frame, bgr, cv::COLOR_BGRA2BGR);
  else if (frame.channels() == 1)
    cv::cvtColor(frame, bgr, cv::COLOR_GRAY2BGR);
  else
    throw std::invalid_argument("frames must have 1, 3 or 4 channels");
  if (bgr.depth() != CV_8U && bgr.depth() != CV_16U)
    throw std::invalid_argument("frames must be 8- or 16-bit");
  // RGGB: (even row, even col) = R, (odd, odd) = B, else G (sim::bayer_rggb, in one pass with the
  // scaling). 8-bit v -> round(v * top / 255) by a table; 16-bit v -> v >> (16 - bits).
  uint16_t lut[256];
  for (int v = 0; v < 256; ++v) lut[v] = static_cast<uint16_t>((v * top + 127) / 255);
  const int shift = 16 - bits;
  cv::Mat out(bgr.size(), CV_16UC1);
  for (int r = 0; r < bgr.rows; ++r) {
    uint16_t* d = out.ptr<uint16_t>(r);
    const int first = (r % 2 == 0) ? 2 : 1, second = (r % 2 == 0) ? 1 : 0;  // BGR index at even / odd column
    if (bgr.depth() == CV_8U) {
      const uint8_t* p = bgr.ptr<uint8_t>(r);
      for (int c = 0; c < bgr.cols; ++c) d[c] = lut[p[3 * c + ((c & 1) ? second : first)]];
    } else {
      const uint16_t* p = bgr.ptr<uint16_t>(r);
      for (int c = 0; c < bgr.cols; ++c)
        d[c] = static_cast<uint16_t>(p[3 * c + ((c & 1) ? second : first)] >> shift);
    }
  }
  return out;
}

// ---- writer --------------------------------------------------------------------------------

struct RecordingWriter::Impl {
  fs::path dir;
  RecordingManifest manifest;
  Options opt;
  struct Stream {
    Hid file, frames, seq, t;
    int64_t n = 0;
    int w = 0, h = 0;
  };
  std::vector<Stream> streams;
  std::chrono::steady_clock::time_point last_flush = std::chrono::steady_clock::now();
  bool closed = false;
};

namespace {

Hid make_dataset(hid_t file, const char* name, hid_t type, int rank, const hsize_t* dims,
                 const hsize_t* chunk, const void* fill) {
  std::vector<hsize_t> zero(dims, dims + rank), maxd(dims, dims + rank);
  zero[0] = 0;
  maxd[0] = H5S_UNLIMITED;
  Hid space(H5Screate_simple(rank, zero.data(), maxd.data()));
  Hid dcpl(H5Pcreate(H5P_DATASET_CREATE));
  H5Pset_chunk(dcpl, rank, chunk);
  if (fill) H5Pset_fill_value(dcpl, type, fill);
  return Hid(H5Dcreate2(file, name, type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT));
}

// Appends one element (a frame or a number) at index n of a 1-D/3-D dataset grown by one.
bool append_row(hid_t ds, hid_t type, int rank, const hsize_t* elem_dims, int64_t n, const void* data) {
  std::vector<hsize_t> size(elem_dims, elem_dims + rank), start(rank, 0), count(elem_dims, elem_dims + rank);
  size[0] = hsize_t(n + 1);
  start[0] = hsize_t(n);
  count[0] = 1;
  if (H5Dset_extent(ds, size.data()) < 0) return false;
  Hid fspace(H5Dget_space(ds));
  if (H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr) < 0)
    return false;
  Hid mspace(H5Screate_simple(rank, count.data(), nullptr));
  return H5Dwrite(ds, type, mspace, fspace, H5P_DEFAULT, data) >= 0;
}

// The self-describing attributes of stream `c` (header comment), written before SWMR starts.
template <typename Stream>
void write_stream_description(const Stream& s, int c, const RecordingManifest& m,
                              const std::string& rig_json) {
  const RigCamera& cam = m.rig.cameras[c];
  const hid_t f = s.file;
  write_string_attr(f, "format", "omma-recording");
  write_int_attr(f, "version", 1);
  write_string_attr(f, "creator", "omma " + version());
  write_int_attr(f, "camera_index", c);
  write_int_attr(f, "bit_depth_readout", m.bits);
  write_string_attr(f, "bayer_pattern", "RGGB");
  write_array_attr<uint8_t>(f, "cfa_pattern", H5T_NATIVE_UINT8, {0, 1, 1, 2});
  write_array_attr<int64_t>(f, "cfa_repeat_pattern_dim", H5T_NATIVE_INT64, {2, 2});
  const double rate = c < int(m.camera_fps.size()) ? m.camera_fps[c] : 0;
  write_double_attr(f, "frame_rate_hz", rate);
  write_double_attr(f, "frame_time", rate > 0 ? 1 / rate : 0);
  write_double_attr(f, "frame_set_rate_hz", m.fps);
  if (m.exposure_s > 0) write_double_attr(f, "count_time", m.exposure_s);
  write_string_attr(f, "sensor_mode", m.sensor_mode);
  write_int_attr(f, "sensor_width", cam.in.width);
  write_int_attr(f, "sensor_height", cam.in.height);
  write_double_attr(f, "clock_mhz", m.clock_mhz);
  write_string_attr(f, "time_base", kTimeBase);
  write_int_attr(f, "start_unix_ns", m.start_unix_ns);
  const std::string start = iso8601_utc(m.start_unix_ns);
  write_string_attr(f, "start_time", start);
  write_string_attr(f, "rig", rig_json);
  write_string_attr(s.frames, "units", "counts");
  write_string_attr(s.frames, "long_name",
                    fmt::format("raw Bayer mosaic (RGGB), {} significant bits in the low bits", m.bits));
  write_string_attr(s.frames, "bayer_pattern", "RGGB");
  write_string_attr(s.seq, "units", "1");
  write_string_attr(s.seq, "long_name", "the source's frame sequence number (gaps: dropped frames)");
  write_string_attr(s.t, "units", "ns");
  write_string_attr(s.t, "long_name", "capture time since the recording's start (-1: frame not written)");
  write_string_attr(s.t, "start", start);
  write_int_attr(s.t, "start_unix_ns", m.start_unix_ns);
  write_string_attr(s.t, "time_base", kTimeBase);
}

}  // namespace

RecordingWriter::RecordingWriter(const fs::path& dir, RecordingManifest manifest, Options options)
    : impl_(std::make_unique<Impl>()) {
  quiet_hdf5();
  std::lock_guard lock(h5_mutex());
  if (!(options.flush_interval_s > 0)) throw std::invalid_argument("flush interval must be positive");
  manifest.files.clear();
  for (const RigCamera& c : manifest.rig.cameras) manifest.files.push_back(stream_name(c.id));
  if (manifest.start_unix_ns == 0)
    manifest.start_unix_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                 std::chrono::system_clock::now().time_since_epoch())
                                 .count();
  manifest.complete = false;
  // The reader's bounds: never a recording that the reader refuses.
  if (std::string why; !manifest.IsValid(&why)) throw std::invalid_argument("recording manifest: " + why);
  std::error_code ec;
  if (fs::exists(dir) && !(fs::is_directory(dir) && fs::is_empty(dir)))
    throw RecordingError("'" + dir.string() + "' exists and is not an empty folder");
  fs::create_directories(dir, ec);
  if (ec) throw RecordingError("cannot create '" + dir.string() + "': " + ec.message());
  impl_->dir = dir;
  impl_->opt = options;
  impl_->manifest = manifest;
  write_text_atomically(dir / "manifest.json", manifest.to_json().dump(2) + "\n");
  const std::string rig_json = rig_to_json(manifest.rig).dump();
  for (size_t c = 0; c < manifest.rig.cameras.size(); ++c) {
    const RigCamera& cam = manifest.rig.cameras[c];
    Impl::Stream s;
    s.w = cam.in.width;
    s.h = cam.in.height;
    const fs::path path = dir / manifest.files[c];
    Hid fapl(H5Pcreate(H5P_FILE_ACCESS));
    H5Pset_libver_bounds(fapl, H5F_LIBVER_LATEST, H5F_LIBVER_LATEST);  // SWMR needs the latest format
    s.file = Hid(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl));
    if (!s.file.ok()) throw RecordingError("cannot create '" + path.string() + "'");
    const hsize_t fd[3] = {0, hsize_t(s.h), hsize_t(s.w)}, fc[3] = {1, hsize_t(s.h), hsize_t(s.w)};
    const hsize_t d1[1] = {0}, c1[1] = {4096};
    const int64_t minus_one = -1;
    s.frames = make_dataset(s.file, "frames", H5T_NATIVE_UINT16, 3, fd, fc, nullptr);
    s.seq = make_dataset(s.file, "seq", H5T_NATIVE_UINT64, 1, d1, c1, nullptr);
    s.t = make_dataset(s.file, "t_ns", H5T_NATIVE_INT64, 1, d1, c1, &minus_one);
    if (!s.frames.ok() || !s.seq.ok() || !s.t.ok())
      throw RecordingError("cannot create the datasets of '" + path.string() + "'");
    write_int_attr(s.file, "width", s.w);
    write_int_attr(s.file, "height", s.h);
    write_int_attr(s.file, "bits", manifest.bits);
    write_int_attr(s.file, "camera", cam.id);
    write_stream_description(s, int(c), manifest, rig_json);
    if (H5Fstart_swmr_write(s.file) < 0)
      throw RecordingError("cannot start SWMR writing of '" + path.string() + "'");
    impl_->streams.push_back(std::move(s));
  }
}

RecordingWriter::~RecordingWriter() {
  std::lock_guard lock(h5_mutex());
  impl_->streams.clear();
}

int64_t RecordingWriter::frames(int cam) const { return impl_->streams.at(cam).n; }

void RecordingWriter::append(int cam, const cv::Mat& raw, uint64_t seq, int64_t t_ns) {
  if (cam < 0 || cam >= static_cast<int>(impl_->streams.size()))
    throw std::invalid_argument(fmt::format("camera index {} out of range", cam));
  {
    std::lock_guard lock(h5_mutex());
    Impl::Stream& s = impl_->streams[cam];
    if (raw.type() != CV_16UC1 || raw.cols != s.w || raw.rows != s.h)
      throw std::invalid_argument(fmt::format("camera {}: raw frame must be CV_16UC1 {}x{}",
                                              impl_->manifest.rig.cameras[cam].id, s.w, s.h));
    const cv::Mat m = raw.isContinuous() ? raw : raw.clone();
    // Room for two frames and 1 MiB for the metadata and the final flush (writable_bytes); the
    // size is HDF5's end of allocation (it writes the next chunk there).
    const uint64_t need = 2 * m.total() * 2 + (1 << 20);
    hsize_t size = 0;
    H5Fget_filesize(s.file, &size);
    if (const uint64_t left = writable_bytes(impl_->dir, size); left < need)
      throw RecordingError(
          fmt::format("disk full: {} bytes left for '{}', a frame needs {} with its margin; stopped "
                      "after frame {} of camera {}",
                      left, (impl_->dir / impl_->manifest.files[cam]).string(), need, s.n,
                      impl_->manifest.rig.cameras[cam].id));
    const hsize_t fd[3] = {1, hsize_t(s.h), hsize_t(s.w)}, d1[1] = {1};
    // The frame first, its t_ns last: a frame counts once its t_ns is written (header comment).
    if (!append_row(s.frames, H5T_NATIVE_UINT16, 3, fd, s.n, m.data) ||
        !append_row(s.seq, H5T_NATIVE_UINT64, 1, d1, s.n, &seq) ||
        !append_row(s.t, H5T_NATIVE_INT64, 1, d1, s.n, &t_ns))
      throw RecordingError(fmt::format("camera {}: cannot write frame {} to '{}' (disk full?)",
                                       impl_->manifest.rig.cameras[cam].id, s.n,
                                       (impl_->dir / impl_->manifest.files[cam]).string()));
    ++s.n;
    bytes_ += m.total() * 2;
  }
  if (std::chrono::steady_clock::now() - impl_->last_flush >
      std::chrono::duration<double>(impl_->opt.flush_interval_s))
    flush();
}

void RecordingWriter::flush() {
  std::lock_guard lock(h5_mutex());
  for (auto& s : impl_->streams)
    if (H5Fflush(s.file, H5F_SCOPE_LOCAL) < 0)
      throw RecordingError("cannot flush the recording (disk full?)");
  impl_->last_flush = std::chrono::steady_clock::now();
}

void RecordingWriter::close() {
  if (impl_->closed) return;
  flush();
  {
    std::lock_guard lock(h5_mutex());
    impl_->streams.clear();
  }
  impl_->manifest.complete = true;
  write_text_atomically(impl_->dir / "manifest.json", impl_->manifest.to_json().dump(2) + "\n");
  impl_->closed = true;
}

// ---- matching ------------------------------------------------------------------------------

MatchResult match_frame_sets(const std::vector<std::vector<FrameMeta>>& metas, int64_t period_ns) {
  if (period_ns <= 0) throw std::invalid_argument("the frame period must be positive");
  MatchResult r;
  const int n = static_cast<int>(metas.size());
  r.cameras.resize(n);
  const int64_t half = period_ns / 2;
  // Per camera: checks, drop and duplicate counts, the span of its frames.
  int64_t min_first = INT64_MAX, max_first = INT64_MIN, min_last = INT64_MAX, max_last = INT64_MIN;
  for (int c = 0; c < n; ++c) {
    CameraMatchStats& st = r.cameras[c];
    st.frames = static_cast<int64_t>(metas[c].size());
    for (size_t i = 0; i < metas[c].size(); ++i) {
      if (metas[c][i].t_ns < 0)
        throw RecordingError(
            fmt::format("stream {}: negative timestamp at frame {} ({} ns)", c, i, metas[c][i].t_ns));
      if (i == 0) continue;
      const FrameMeta &a = metas[c][i - 1], &b = metas[c][i];
      if (b.t_ns < a.t_ns)
        throw RecordingError(fmt::format("stream {}: timestamps go backwards at frame {} ({} ns after {} ns)",
                                         c, i, b.t_ns, a.t_ns));
      if (b.seq == a.seq)
        ++st.duplicates;
      else if (b.seq > a.seq)  // saturating: sequence numbers are the file's, any uint64
        st.dropped = int64_t(std::min<uint64_t>(
            uint64_t(st.dropped) + std::min<uint64_t>(b.seq - a.seq - 1, INT64_MAX), INT64_MAX));
      else
        throw RecordingError(fmt::format("stream {}: sequence numbers go backwards at frame {}", c, i));
    }
    if (metas[c].empty()) continue;
    min_first = std::min(min_first, metas[c].front().t_ns);
    max_first = std::max(max_first, metas[c].front().t_ns);
    min_last = std::min(min_last, metas[c].back().t_ns);
    max_last = std::max(max_last, metas[c].back().t_ns);
  }
  if (min_first == INT64_MAX) return r;  // no frame at all
  // The clock's first and last instants (header comment); all times >= 0, so no difference overflows.
  const int64_t t0 = max_first - min_first <= period_ns ? std::max(min_first, max_first - half) : min_first;
  const int64_t end = (max_last - min_last <= period_ns ? min_last : max_last) - t0;  // + half, relative
  std::vector<size_t> next(n, 0);  // per camera: its first frame not yet in a set nor passed
  std::vector<int64_t> used(n, 0);
  for (int64_t k = 0;; ++k) {
    if (k > (INT64_MAX - half) / period_ns) break;
    int64_t at = k * period_ns;  // T_k - t0
    if (at - half > end) break;  // (no overflow: 0 <= at, half)
    // An instant with no frame near: jump to the first instant within half a period of the next frame.
    int64_t soonest = INT64_MAX;
    for (int c = 0; c < n; ++c) {
      while (next[c] < metas[c].size() && metas[c][next[c]].t_ns - t0 < at - half) ++next[c];
      if (next[c] < metas[c].size()) soonest = std::min(soonest, metas[c][next[c]].t_ns - t0);
    }
    if (soonest == INT64_MAX) break;
    if (soonest > at + half) {
      const int64_t lead = soonest - half;  // the first k with T_k >= t - half (no overflow)
      const int64_t jump = lead / period_ns + (lead % period_ns != 0);
      if (jump <= k) continue;  // cannot happen (soonest > at + half); keeps the loop finite
      k = jump - 1;
      continue;
    }
    FrameSet set{t0 + at, std::vector<int64_t>(n, -1)};
    bool any = false, complete = true;
    for (int c = 0; c < n; ++c) {
      int64_t best = -1, best_d = INT64_MAX;
      for (size_t i = next[c]; i < metas[c].size() && metas[c][i].t_ns - t0 <= at + half; ++i) {
        if (i > 0 && metas[c][i].seq == metas[c][i - 1].seq) continue;  // a duplicate: never in a set
        const int64_t d = std::abs(metas[c][i].t_ns - t0 - at);
        if (d < best_d) best = int64_t(i), best_d = d;
      }
      if (best >= 0) {
        set.frame[c] = best;
        next[c] = size_t(best) + 1;  // earlier frames in the window are left out
        ++used[c];
        any = true;
      } else {
        complete = false;
      }
    }
    if (!any) continue;
    for (int c = 0; c < n; ++c)
      if (set.frame[c] < 0) ++r.cameras[c].missing;
    r.complete_sets += complete;
    if (int64_t(r.sets.size() + 1) > kMaxFrameSetEntries / std::max(n, 1))
      throw RecordingError(fmt::format("more than {} frame sets of {} cameras (at most {} frame indices)",
                                       r.sets.size(), n, kMaxFrameSetEntries));
    r.sets.push_back(std::move(set));
  }
  for (int c = 0; c < n; ++c) r.cameras[c].extra = r.cameras[c].frames - used[c];
  return r;
}

IncompletePolicy parse_incomplete_policy(const std::string& s) {
  if (s == "skip") return IncompletePolicy::kSkip;
  if (s == "hold") return IncompletePolicy::kHold;
  if (s == "fail") return IncompletePolicy::kFail;
  throw std::invalid_argument("--incomplete must be skip, hold or fail, got '" + s + "'");
}

const char* incomplete_policy_name(IncompletePolicy p) {
  switch (p) {
    case IncompletePolicy::kSkip:
      return "skip";
    case IncompletePolicy::kHold:
      return "hold";
    case IncompletePolicy::kFail:
      return "fail";
  }
  return "?";
}

bool FrameSetPlanOptions::IsValid(std::string* why) const {
  if (max_hold_age_ns < 0) return invalid(why, "the hold age limit must be >= 0");
  return true;
}

json FrameSetPlan::to_json() const {
  return {{"policy", incomplete_policy_name(policy)},
          {"max_hold_age_s", policy == IncompletePolicy::kHold ? json(max_hold_age_ns / 1e9) : json(nullptr)},
          {"frame_sets", considered},
          {"complete", complete},
          {"incomplete", incomplete},
          {"held_sets", held_sets},
          {"held_frames", held_frames},
          {"max_held_age_s", max_held_age_ns / 1e9},
          {"skipped", skipped},
          {"skipped_sets", skipped_sets},
          {"rendered", int64_t(sets.size())},
          {"holes", 0}};
}

FrameSetPlan plan_frame_sets(const MatchResult& match, const std::vector<std::vector<FrameMeta>>& metas,
                             int64_t first, int64_t last, int64_t period_ns, const FrameSetPlanOptions& o,
                             const std::vector<int>& ids) {
  if (std::string why; !o.IsValid(&why)) throw std::invalid_argument(why);
  if (period_ns <= 0) throw std::invalid_argument("the frame period must be positive");
  const int64_t count = int64_t(match.sets.size());
  if (first < 0 || last >= count || (last < first && count > 0))
    throw std::invalid_argument(fmt::format("frame sets {}..{} outside 0..{}", first, last, count - 1));
  FrameSetPlan p;
  p.policy = o.policy;
  if (o.policy == IncompletePolicy::kHold)
    p.max_hold_age_ns =
        o.max_hold_age_ns > 0 ? o.max_hold_age_ns : (period_ns > INT64_MAX / 2 ? INT64_MAX : 2 * period_ns);
  auto id = [&](size_t c) { return c < ids.size() ? ids[c] : int(c); };
  for (int64_t s = first; s <= last && s < count; ++s) {
    const FrameSet& fs = match.sets[s];
    ++p.considered;
    std::vector<size_t> lacking;
    for (size_t c = 0; c < fs.frame.size(); ++c)
      if (fs.frame[c] < 0) lacking.push_back(c);
    PlannedSet ps{s, fs.frame, std::vector<int64_t>(fs.frame.size(), 0)};
    if (lacking.empty()) {
      ++p.complete;
      p.sets.push_back(std::move(ps));
      continue;
    }
    ++p.incomplete;
    if (o.policy == IncompletePolicy::kFail) {
      int64_t total = 0;
      for (int64_t k = first; k <= last && k < count; ++k)
        for (const int64_t f : match.sets[k].frame)
          if (f < 0) {
            ++total;
            break;
          }
      std::vector<int> lacking_ids;
      for (const size_t c : lacking) lacking_ids.push_back(id(c));
      throw RecordingError(fmt::format(
          "frame set {} lacks camera(s) {}; {} of {} frame sets are incomplete (--incomplete skip leaves "
          "them out, --incomplete hold fills them with the cameras' last frames)",
          s, fmt::join(lacking_ids, ", "), total, std::min(last, count - 1) - first + 1));
    }
    bool filled = o.policy == IncompletePolicy::kHold;
    int64_t held = 0, oldest = 0;
    for (size_t c = 0; c < lacking.size() && filled; ++c) {
      const auto& m = metas[lacking[c]];
      // The camera's last frame captured at or before the set's instant.
      const auto it = std::upper_bound(m.begin(), m.end(), fs.t_ns,
                                       [](int64_t t, const FrameMeta& f) { return t < f.t_ns; });
      if (it == m.begin()) {
        filled = false;
        break;
      }
      const int64_t age = fs.t_ns - std::prev(it)->t_ns;
      if (age > p.max_hold_age_ns) {
        filled = false;
        break;
      }
      ps.frame[lacking[c]] = int64_t(std::prev(it) - m.begin());
      ps.held_age_ns[lacking[c]] = age;
      ++held;
      oldest = std::max(oldest, age);
    }
    if (filled) {
      ++p.held_sets;
      p.held_frames += held;
      p.max_held_age_ns = std::max(p.max_held_age_ns, oldest);
      p.sets.push_back(std::move(ps));
    } else {
      ++p.skipped;
      if (p.skipped_sets.size() < 1000) p.skipped_sets.push_back(s);
    }
  }
  return p;
}

// ---- reader --------------------------------------------------------------------------------

struct RecordingReader::Impl {
  struct Stream {
    Hid file, frames;
    int w = 0, h = 0;
    std::string where;  // "camera ID: stream 'PATH'", the start of every error about it
  };
  std::vector<Stream> streams;
  fs::path dir;
};

namespace {

const char* file_kind(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// Refuses, before anything opens it, all but a regular file `name` in `dir` (a symbolic link must
// resolve to a file directly in the folder); returns its size. `what` starts every error.
uint64_t regular_file_in(const fs::path& dir, const std::string& name, const std::string& what) {
  const fs::path p = dir / name;
  struct stat st {};
  if (::lstat(p.c_str(), &st) != 0) {
    if (errno == ENOENT) throw RecordingError(what + " is missing");
    throw RecordingError(what + " cannot be read: " + std::strerror(errno));
  }
  if (S_ISLNK(st.st_mode)) {
    std::error_code e1, e2;
    const fs::path target = fs::canonical(p, e1), home = fs::canonical(dir, e2);
    if (e1) throw RecordingError(what + " is a broken symbolic link");
    if (e2 || target.parent_path() != home)
      throw RecordingError(what + " is a symbolic link out of the recording's folder (to '" +
                           target.string() + "')");
    if (::stat(p.c_str(), &st) != 0) throw RecordingError(what + " cannot be read: " + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode))
    throw RecordingError(what + " is " + file_kind(st.st_mode) + ", not a regular file");
  return uint64_t(st.st_size);
}

// Integer attribute `name` of `obj` (one element of any integer type), or nullopt if it is missing
// or is not one integer.
std::optional<int64_t> int_attr(hid_t obj, const char* name) {
  if (H5Aexists(obj, name) <= 0) return std::nullopt;
  Hid a(H5Aopen(obj, name, H5P_DEFAULT));
  if (!a.ok()) return std::nullopt;
  Hid space(H5Aget_space(a)), type(H5Aget_type(a));
  if (!space.ok() || !type.ok() || H5Sget_simple_extent_npoints(space) != 1 ||
      H5Tget_class(type) != H5T_INTEGER)
    return std::nullopt;
  int64_t v = 0;
  if (H5Aread(a, H5T_NATIVE_INT64, &v) < 0) return std::nullopt;
  return v;
}

// Opens dataset `name` of a stream: a hard link in the root group to a chunked dataset stored in
// the file (no external storage, no virtual layout, no filters) of `rank` dimensions and integers of
// `bytes` bytes and `sign`. Its extent and chunk shape into dims and chunk. Throws RecordingError
// starting with `where`.
Hid open_dataset(hid_t file, const char* name, int rank, size_t bytes, H5T_sign_t sign, hsize_t* dims,
                 hsize_t* chunk, const std::string& where) {
  if (H5Lexists(file, name, H5P_DEFAULT) <= 0)
    throw RecordingError(fmt::format("{} lacks '{}'", where, name));
  H5L_info_t li{};
  if (H5Lget_info(file, name, &li, H5P_DEFAULT) < 0 || li.type != H5L_TYPE_HARD)
    throw RecordingError(fmt::format("{}: '{}' is a link, not a dataset stored in the file", where, name));
  Hid ds(H5Dopen2(file, name, H5P_DEFAULT));
  if (!ds.ok()) throw RecordingError(fmt::format("{}: '{}' cannot be opened (damaged stream)", where, name));
  Hid dcpl(H5Dget_create_plist(ds)), type(H5Dget_type(ds)), space(H5Dget_space(ds));
  if (!dcpl.ok() || !type.ok() || !space.ok())
    throw RecordingError(fmt::format("{}: '{}' cannot be read (damaged stream)", where, name));
  if (H5Pget_layout(dcpl) != H5D_CHUNKED || H5Pget_external_count(dcpl) != 0)
    throw RecordingError(fmt::format(
        "{}: '{}' is not chunked in the file (external, virtual or contiguous storage)", where, name));
  if (H5Pget_nfilters(dcpl) != 0)
    throw RecordingError(fmt::format("{}: '{}' is filtered (compressed)", where, name));
  if (H5Tget_class(type) != H5T_INTEGER || H5Tget_size(type) != bytes || H5Tget_sign(type) != sign)
    throw RecordingError(fmt::format("{}: '{}' must hold {}signed {}-bit integers", where, name,
                                     sign == H5T_SGN_NONE ? "un" : "", 8 * bytes));
  if (H5Sget_simple_extent_type(space) != H5S_SIMPLE || H5Sget_simple_extent_ndims(space) != rank ||
      H5Sget_simple_extent_dims(space, dims, nullptr) != rank || H5Pget_chunk(dcpl, rank, chunk) != rank)
    throw RecordingError(
        fmt::format("{}: '{}' must have {} dimension{}", where, name, rank, rank > 1 ? "s" : ""));
  return ds;
}

}  // namespace

RecordingReader::RecordingReader(const fs::path& dir) : impl_(std::make_unique<Impl>()) {
  quiet_hdf5();
  impl_->dir = dir;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw RecordingError("recording '" + dir.string() + "' is not a folder");
  const fs::path mpath = dir / "manifest.json";
  if (!fs::exists(fs::symlink_status(mpath, ec)))
    throw RecordingError("recording '" + dir.string() + "' has no manifest.json");
  regular_file_in(dir, "manifest.json", "'" + mpath.string() + "'");
  json j;
  try {
    j = json::parse(read_text_file(mpath, kMaxTextFileBytes, "recording manifest"));
  } catch (const json::exception& e) {
    throw RecordingError("'" + mpath.string() + "' is not valid JSON: " + e.what());
  } catch (const IoError& e) {
    throw RecordingError(e.what());
  }
  manifest_ = RecordingManifest::from_json(j);
  std::lock_guard lock(h5_mutex());
  for (size_t c = 0; c < manifest_.files.size(); ++c) {
    const fs::path path = dir / manifest_.files[c];
    const RigCamera& cam = manifest_.rig.cameras[c];
    const std::string where = fmt::format("camera {}: stream '{}'", cam.id, path.string());
    regular_file_in(dir, manifest_.files[c], where);
    Impl::Stream s;
    s.where = where;
    Hid fapl(H5Pcreate(H5P_FILE_ACCESS));
    if (!fapl.ok() || H5Pset_metadata_read_attempts(fapl, kRecordingReadAttempts) < 0 ||
        H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG) < 0)
      throw RecordingError(where + ": cannot set up HDF5");
    s.file = Hid(H5Fopen(path.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, fapl));
    if (!s.file.ok()) throw RecordingError(where + " is truncated, damaged or not an HDF5 file");
    // Exactly the three datasets, hard-linked.
    H5G_info_t gi{};
    if (H5Gget_info(s.file, &gi) < 0)
      throw RecordingError(where + ": its root group cannot be read (damaged stream)");
    if (gi.nlinks != 3)
      throw RecordingError(
          fmt::format("{} holds {} objects, not the 3 datasets frames, seq and t_ns", where, gi.nlinks));
    hsize_t fd[3] = {0, 0, 0}, fc[3] = {0, 0, 0}, ds[1] = {0}, dc[1] = {0}, dt[1] = {0}, tc[1] = {0};
    s.frames = open_dataset(s.file, "frames", 3, 2, H5T_SGN_NONE, fd, fc, where);
    Hid seq = open_dataset(s.file, "seq", 1, 8, H5T_SGN_NONE, ds, dc, where);
    Hid t = open_dataset(s.file, "t_ns", 1, 8, H5T_SGN_2, dt, tc, where);
    // The sizes, 64-bit, against the manifest's camera before anything is narrowed.
    const auto& in = cam.in;
    if (fd[1] != hsize_t(in.height) || fd[2] != hsize_t(in.width))
      throw RecordingError(
          fmt::format("{}: frames are {}x{} but the rig's camera is {}x{} (mismatched sensor mode)", where,
                      fd[2], fd[1], in.width, in.height));
    s.h = in.height;
    s.w = in.width;
    if (fc[0] != 1 || fc[1] != fd[1] || fc[2] != fd[2])
      throw RecordingError(fmt::format("{}: frames must be stored one frame per chunk", where));
    if (dc[0] < 1 || dc[0] > (1u << 20) || tc[0] < 1 || tc[0] > (1u << 20))
      throw RecordingError(fmt::format("{}: seq and t_ns must have chunks of 1..2^20 elements", where));
    // The stream's own attributes: its camera, size and bit depth are the manifest's.
    const auto a_cam = int_attr(s.file, "camera"), a_w = int_attr(s.file, "width"),
               a_h = int_attr(s.file, "height"), a_bits = int_attr(s.file, "bits");
    if (!a_cam || !a_w || !a_h || !a_bits)
      throw RecordingError(where + " lacks one of its integer attributes camera, width, height, bits");
    if (*a_cam != cam.id)
      throw RecordingError(
          fmt::format("{} holds the frames of camera {}, not of camera {} (manifest and stream "
                      "disagree)",
                      where, *a_cam, cam.id));
    if (*a_w != in.width || *a_h != in.height)
      throw RecordingError(fmt::format("{}: its attributes say {}x{}, the rig's camera is {}x{}", where, *a_w,
                                       *a_h, in.width, in.height));
    if (*a_bits != manifest_.bits)
      throw RecordingError(
          fmt::format("{}: its attributes say {} bits, the manifest {}", where, *a_bits, manifest_.bits));
    // The extents against the file's size (taken after them: a file being written only grows). One
    // frame more than fits is a recorder stopped between growing the datasets and writing the frame.
    const hsize_t n = std::min({fd[0], ds[0], dt[0]});
    const uint64_t per_frame = 2 * uint64_t(in.width) * uint64_t(in.height) + 16;
    const uint64_t file_size = regular_file_in(dir, manifest_.files[c], where);
    if (n > file_size / per_frame + 1)
      throw RecordingError(
          fmt::format("{} declares {} frames of {}x{}, more than its {} bytes hold (damaged or "
                      "forged stream)",
                      where, n, in.width, in.height, file_size));
    // Complete frames: those whose t_ns was written (>= 0), within every dataset's extent.
    std::vector<int64_t> tv(n);
    std::vector<uint64_t> sv(n);
    if (n > 0) {  // the first n elements (the extents differ after a crash)
      Hid mt(H5Screate_simple(1, &n, nullptr));
      Hid f1(H5Dget_space(t)), f2(H5Dget_space(seq));
      const hsize_t start[1] = {0};
      if (H5Sselect_hyperslab(f1, H5S_SELECT_SET, start, nullptr, &n, nullptr) < 0 ||
          H5Sselect_hyperslab(f2, H5S_SELECT_SET, start, nullptr, &n, nullptr) < 0 ||
          H5Dread(t, H5T_NATIVE_INT64, mt, f1, H5P_DEFAULT, tv.data()) < 0 ||
          H5Dread(seq, H5T_NATIVE_UINT64, mt, f2, H5P_DEFAULT, sv.data()) < 0)
        throw RecordingError(where + ": its timestamps cannot be read (damaged stream)");
    }
    std::vector<FrameMeta> meta;
    for (hsize_t i = 0; i < n && tv[i] >= 0; ++i) meta.push_back({sv[i], tv[i]});
    metas_.push_back(std::move(meta));
    impl_->streams.push_back(std::move(s));
  }
  try {
    match_ = match_frame_sets(metas_, period_ns());
  } catch (const RecordingError& e) {
    throw RecordingError(fmt::format("recording '{}': {}", dir.string(), e.what()));
  }
}

RecordingReader::~RecordingReader() {
  std::lock_guard lock(h5_mutex());
  impl_->streams.clear();
}

cv::Mat RecordingReader::read(int cam, int64_t i) const {
  if (cam < 0 || cam >= cameras() || i < 0 || i >= frames(cam))
    throw RecordingError(fmt::format("frame {} of stream {} does not exist", i, cam));
  const Impl::Stream& s = impl_->streams[cam];
  cv::Mat out(s.h, s.w, CV_16UC1);
  {
    std::lock_guard lock(h5_mutex());
    const hsize_t start[3] = {hsize_t(i), 0, 0}, count[3] = {1, hsize_t(s.h), hsize_t(s.w)};
    // Stored in the file, uncompressed: an unwritten chunk would read as zeros.
    hsize_t stored = 0;
    if (H5Dget_chunk_storage_size(s.frames, start, &stored) < 0 || stored != out.total() * 2)
      throw RecordingError(
          fmt::format("{}: frame {} is not stored in the file (damaged stream)", s.where, i));
    Hid fspace(H5Dget_space(s.frames));
    Hid mspace(H5Screate_simple(3, count, nullptr));
    if (H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, nullptr, count, nullptr) < 0 ||
        H5Dread(s.frames, H5T_NATIVE_UINT16, mspace, fspace, H5P_DEFAULT, out.data) < 0)
      throw RecordingError(fmt::format("{}: cannot read frame {} (damaged stream)", s.where, i));
  }
  // The bit depth the renderer develops with (the same test as its ISP's).
  double mx = 0;
  cv::minMaxLoc(out, nullptr, &mx);
  if (mx > double((1 << manifest_.bits) - 1))
    throw RecordingError(
        fmt::format("{}: frame {} has values up to {}, more than the recording's {} bits allow "
                    "(damaged stream or wrong bit depth)",
                    s.where, i, mx, manifest_.bits));
  return out;
}

std::vector<cv::Mat> RecordingReader::read_frames(const std::vector<int64_t>& frame) const {
  if (int(frame.size()) != cameras())
    throw RecordingError(fmt::format("{} frame indices for {} cameras", frame.size(), cameras()));
  std::vector<cv::Mat> out(cameras());
  for (int c = 0; c < cameras(); ++c)
    if (frame[c] >= 0) out[c] = read(c, frame[c]);
  return out;
}

int64_t RecordingReader::period_ns() const { return std::max<int64_t>(1, int64_t(1e9 / manifest_.fps)); }

FrameSetPlan RecordingReader::plan(int64_t first, int64_t last, const FrameSetPlanOptions& options) const {
  std::vector<int> ids;
  for (const RigCamera& c : manifest_.rig.cameras) ids.push_back(c.id);
  return plan_frame_sets(match_, metas_, first, last, period_ns(), options, ids);
}

std::string rig_mismatch(const Rig& rig, const Rig& recorded) {
  if (rig.cameras.size() != recorded.cameras.size())
    return fmt::format("has {} cameras, the recording {}", rig.cameras.size(), recorded.cameras.size());
  for (size_t c = 0; c < rig.cameras.size(); ++c) {
    const Intrinsics& a = rig.cameras[c].in;
    const Intrinsics& b = recorded.cameras[c].in;
    if (a.width != b.width || a.height != b.height)
      return fmt::format("camera {} is {}x{}, the recording's {}x{} (another sensor mode)", rig.cameras[c].id,
                         a.width, a.height, b.width, b.height);
  }
  return "";
}

std::vector<cv::Mat> RecordingReader::read_frame_set(int64_t i) const {
  if (i < 0 || i >= frame_sets())
    throw RecordingError(fmt::format("frame set {} does not exist ({} sets)", i, frame_sets()));
  return read_frames(match_.sets[i].frame);
}

}  // namespace omma::io
