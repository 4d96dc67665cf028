#include "omma/io/recording.h"

#include <sys/resource.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <chrono>
#include <mutex>

#include <fmt/format.h>
#include <hdf5.h>
#include <opencv2/imgproc.hpp>

#include "omma/core/frames.h"
#include "omma/core/io.h"

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

json RecordingManifest::to_json() const {
  json streams = json::array();
  for (size_t c = 0; c < files.size(); ++c)
    streams.push_back({{"camera", rig.cameras[c].id},
                       {"file", files[c]},
                       {"width", rig.cameras[c].in.width},
                       {"height", rig.cameras[c].in.height}});
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

RecordingManifest RecordingManifest::from_json(const json& j) {
  try {
    if (!j.is_object() || j.value("format", "") != "omma-recording")
      throw RecordingError("not an omma recording manifest (format is not 'omma-recording')");
    if (j.value("version", 0) != 1) throw RecordingError("unsupported recording version");
    RecordingManifest m;
    m.rig = rig_from_json(j.at("rig"));
    m.sensor_mode = j.value("sensor_mode", "full");
    m.clock_mhz = j.value("clock_mhz", 0.0);
    m.fps = j.at("fps").get<double>();
    m.bits = j.at("bits").get<int>();
    m.start_unix_ns = j.value("start_unix_ns", int64_t(0));
    m.complete = j.value("complete", false);
    if (!(m.fps > 0 && m.fps < 1e5)) throw RecordingError("manifest: fps must be positive");
    if (m.bits < 8 || m.bits > 16) throw RecordingError("manifest: bits must be 8..16");
    const json& streams = j.at("streams");
    if (!streams.is_array() || streams.size() != m.rig.cameras.size())
      throw RecordingError(fmt::format("manifest: {} streams for a rig of {} cameras",
                                       streams.is_array() ? streams.size() : 0, m.rig.cameras.size()));
    for (size_t c = 0; c < streams.size(); ++c) {
      const json& s = streams[c];
      const std::string f = s.at("file").get<std::string>();
      if (f.empty() || f.find('/') != std::string::npos || f == "." || f == "..")
        throw RecordingError("manifest: stream file names must be plain names");
      if (s.at("width").get<int>() != m.rig.cameras[c].in.width ||
          s.at("height").get<int>() != m.rig.cameras[c].in.height)
        throw RecordingError(
            fmt::format("manifest: stream {} is {}x{} but camera {} is {}x{} (mismatched sensor mode)", f,
                        s.at("width").get<int>(), s.at("height").get<int>(), m.rig.cameras[c].id,
                        m.rig.cameras[c].in.width, m.rig.cameras[c].in.height));
      m.files.push_back(f);
    }
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

}  // namespace

RecordingWriter::RecordingWriter(const fs::path& dir, RecordingManifest manifest, Options options)
    : impl_(std::make_unique<Impl>()) {
  quiet_hdf5();
  std::lock_guard lock(h5_mutex());
  manifest.rig.validate();
  if (!(options.flush_interval_s > 0)) throw std::invalid_argument("flush interval must be positive");
  std::error_code ec;
  if (fs::exists(dir) && !(fs::is_directory(dir) && fs::is_empty(dir)))
    throw RecordingError("'" + dir.string() + "' exists and is not an empty folder");
  fs::create_directories(dir, ec);
  if (ec) throw RecordingError("cannot create '" + dir.string() + "': " + ec.message());
  impl_->dir = dir;
  impl_->opt = options;
  manifest.files.clear();
  for (const RigCamera& c : manifest.rig.cameras) manifest.files.push_back(stream_name(c.id));
  if (manifest.start_unix_ns == 0)
    manifest.start_unix_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                 std::chrono::system_clock::now().time_since_epoch())
                                 .count();
  manifest.complete = false;
  impl_->manifest = manifest;
  write_text_atomically(dir / "manifest.json", manifest.to_json().dump(2) + "\n");
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
  struct Item {
    int64_t t;
    int cam;
    int64_t index;
  };
  std::vector<Item> all;
  for (int c = 0; c < n; ++c) {
    CameraMatchStats& st = r.cameras[c];
    st.frames = static_cast<int64_t>(metas[c].size());
    for (size_t i = 0; i < metas[c].size(); ++i) {
      if (i > 0) {
        const FrameMeta &a = metas[c][i - 1], &b = metas[c][i];
        if (b.t_ns < a.t_ns)
          throw RecordingError(fmt::format(
              "stream {}: timestamps go backwards at frame {} ({} ns after {} ns)", c, i, b.t_ns, a.t_ns));
        if (b.seq == a.seq)
          ++st.duplicates;
        else if (b.seq > a.seq)
          st.dropped += int64_t(b.seq - a.seq - 1);
        else
          throw RecordingError(fmt::format("stream {}: sequence numbers go backwards at frame {}", c, i));
      }
      all.push_back({metas[c][i].t_ns, c, static_cast<int64_t>(i)});
    }
  }
  std::stable_sort(all.begin(), all.end(), [](const Item& a, const Item& b) { return a.t < b.t; });
  const int64_t half = period_ns / 2;
  FrameSet cur;
  bool open = false;
  auto close_set = [&] {
    if (!open) return;
    bool complete = true;
    for (int c = 0; c < n; ++c)
      if (cur.frame[c] < 0) {
        ++r.cameras[c].missing;
        complete = false;
      }
    r.complete_sets += complete;
    r.sets.push_back(cur);
    open = false;
  };
  for (const Item& it : all) {
    if (open && (it.t - cur.t_ns > half || cur.frame[it.cam] >= 0)) {
      if (it.t - cur.t_ns <= half && cur.frame[it.cam] >= 0 &&
          metas[it.cam][it.index].seq == metas[it.cam][cur.frame[it.cam]].seq) {
        ++r.cameras[it.cam].extra;  // the same frame again within the set: left out
        continue;
      }
      close_set();
    }
    if (!open) {
      cur = FrameSet{it.t, std::vector<int64_t>(n, -1)};
      open = true;
    }
    cur.frame[it.cam] = it.index;
  }
  close_set();
  return r;
}

// ---- reader --------------------------------------------------------------------------------

struct RecordingReader::Impl {
  struct Stream {
    Hid file, frames;
    int w = 0, h = 0;
  };
  std::vector<Stream> streams;
  fs::path dir;
};

RecordingReader::RecordingReader(const fs::path& dir) : impl_(std::make_unique<Impl>()) {
  quiet_hdf5();
  impl_->dir = dir;
  if (!fs::is_directory(dir)) throw RecordingError("recording '" + dir.string() + "' is not a folder");
  const fs::path mpath = dir / "manifest.json";
  if (!fs::exists(mpath)) throw RecordingError("recording '" + dir.string() + "' has no manifest.json");
  json j;
  try {
    j = json::parse(read_text_file(mpath));
  } catch (const json::exception& e) {
    throw RecordingError("'" + mpath.string() + "' is not valid JSON: " + e.what());
  }
  manifest_ = RecordingManifest::from_json(j);
  std::lock_guard lock(h5_mutex());
  for (size_t c = 0; c < manifest_.files.size(); ++c) {
    const fs::path path = dir / manifest_.files[c];
    const int id = manifest_.rig.cameras[c].id;
    if (!fs::exists(path))
      throw RecordingError(fmt::format("camera {}: stream '{}' is missing", id, path.string()));
    Impl::Stream s;
    s.file = Hid(H5Fopen(path.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, H5P_DEFAULT));
    if (!s.file.ok())
      throw RecordingError(
          fmt::format("camera {}: stream '{}' is truncated or not an HDF5 file", id, path.string()));
    s.frames = Hid(H5Dopen2(s.file, "frames", H5P_DEFAULT));
    Hid seq(H5Dopen2(s.file, "seq", H5P_DEFAULT)), t(H5Dopen2(s.file, "t_ns", H5P_DEFAULT));
    if (!s.frames.ok() || !seq.ok() || !t.ok())
      throw RecordingError(
          fmt::format("camera {}: stream '{}' lacks frames, seq or t_ns", id, path.string()));
    hsize_t fd[3] = {0, 0, 0}, ds[1] = {0}, dt[1] = {0};
    Hid fs_(H5Dget_space(s.frames)), ss(H5Dget_space(seq)), ts(H5Dget_space(t));
    if (H5Sget_simple_extent_ndims(fs_) != 3)
      throw RecordingError(fmt::format("camera {}: frames must be 3-D", id));
    H5Sget_simple_extent_dims(fs_, fd, nullptr);
    H5Sget_simple_extent_dims(ss, ds, nullptr);
    H5Sget_simple_extent_dims(ts, dt, nullptr);
    s.h = int(fd[1]);
    s.w = int(fd[2]);
    const auto& in = manifest_.rig.cameras[c].in;
    if (s.w != in.width || s.h != in.height)
      throw RecordingError(
          fmt::format("camera {}: stream frames are {}x{} but the rig's camera is {}x{} (mismatched "
                      "sensor mode)",
                      id, s.w, s.h, in.width, in.height));
    // Complete frames: those whose t_ns was written (>= 0), within every dataset's extent.
    const hsize_t n = std::min({fd[0], ds[0], dt[0]});
    std::vector<int64_t> tv(n);
    std::vector<uint64_t> sv(n);
    if (n > 0) {  // the first n elements (the extents differ after a crash)
      Hid mt(H5Screate_simple(1, &n, nullptr));
      Hid f1(H5Dget_space(t)), f2(H5Dget_space(seq));
      const hsize_t start[1] = {0};
      H5Sselect_hyperslab(f1, H5S_SELECT_SET, start, nullptr, &n, nullptr);
      H5Sselect_hyperslab(f2, H5S_SELECT_SET, start, nullptr, &n, nullptr);
      if (H5Dread(t, H5T_NATIVE_INT64, mt, f1, H5P_DEFAULT, tv.data()) < 0 ||
          H5Dread(seq, H5T_NATIVE_UINT64, mt, f2, H5P_DEFAULT, sv.data()) < 0)
        throw RecordingError(fmt::format("camera {}: cannot read the timestamps of '{}'", id, path.string()));
    }
    std::vector<FrameMeta> meta;
    for (hsize_t i = 0; i < n && tv[i] >= 0; ++i) meta.push_back({sv[i], tv[i]});
    metas_.push_back(std::move(meta));
    impl_->streams.push_back(std::move(s));
  }
  try {
    match_ = match_frame_sets(metas_, static_cast<int64_t>(1e9 / manifest_.fps));
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
  std::lock_guard lock(h5_mutex());
  const Impl::Stream& s = impl_->streams[cam];
  cv::Mat out(s.h, s.w, CV_16UC1);
  const hsize_t start[3] = {hsize_t(i), 0, 0}, count[3] = {1, hsize_t(s.h), hsize_t(s.w)};
  Hid fspace(H5Dget_space(s.frames));
  Hid mspace(H5Screate_simple(3, count, nullptr));
  if (H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, nullptr, count, nullptr) < 0 ||
      H5Dread(s.frames, H5T_NATIVE_UINT16, mspace, fspace, H5P_DEFAULT, out.data) < 0)
    throw RecordingError(
        fmt::format("camera {}: cannot read frame {} (damaged stream)", manifest_.rig.cameras[cam].id, i));
  return out;
}

std::vector<cv::Mat> RecordingReader::read_frame_set(int64_t i) const {
  if (i < 0 || i >= frame_sets())
    throw RecordingError(fmt::format("frame set {} does not exist ({} sets)", i, frame_sets()));
  std::vector<cv::Mat> out(cameras());
  for (int c = 0; c < cameras(); ++c)
    if (match_.sets[i].frame[c] >= 0) out[c] = read(c, match_.sets[i].frame[c]);
  return out;
}

}  // namespace omma::io
