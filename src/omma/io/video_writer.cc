#include "omma/io/video_writer.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/opt.h>
#include <libavutil/pixdesc.h>
#include <libavutil/spherical.h>
#include <libswscale/swscale.h>
}

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <tuple>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "omma/core/io.h"
#include "omma/core/valid.h"
#include "omma/io/metadata.h"
#include "omma/io/spherical_video.h"

namespace omma::io {
namespace fs = std::filesystem;

namespace {

const char* const kPresets[] = {"ultrafast", "superfast", "veryfast", "faster",  "fast",
                                "medium",    "slow",      "slower",   "veryslow"};

// The muxer for an extension ("" if none).
std::string muxer_for(const std::string& ext) {
  if (ext == ".mp4" || ext == ".m4v") return "mp4";
  if (ext == ".mov") return "mov";
  if (ext == ".mkv") return "matroska";
  if (ext == ".webm") return "webm";
  if (ext == ".avi") return "avi";
  return "";
}

// FFmpeg's own messages (x264's statistics, libvpx's notes) only when they are errors.
void quiet_ffmpeg_log() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (av_log_get_level() > AV_LOG_ERROR) av_log_set_level(AV_LOG_ERROR);
  });
}

}  // namespace

std::string to_string(VideoCodec codec) {
  switch (codec) {
    case VideoCodec::kAuto:
      return "auto";
    case VideoCodec::kH264:
      return "h264";
    case VideoCodec::kVp9:
      return "vp9";
  }
  return "?";
}

std::string to_string(VideoPreset preset) {
  const int i = int(preset);
  return i >= 0 && i < int(std::size(kPresets)) ? kPresets[i] : "?";
}

VideoPreset parse_video_preset(const std::string& name) {
  for (int i = 0; i < int(std::size(kPresets)); ++i)
    if (name == kPresets[i]) return VideoPreset(i);
  throw std::invalid_argument(
      "video preset '" + name +
      "' is not one of ultrafast superfast veryfast faster fast medium slow slower veryslow");
}

VideoCodec parse_video_codec(const std::string& name) {
  if (name == "auto") return VideoCodec::kAuto;
  if (name == "h264" || name == "x264" || name == "avc") return VideoCodec::kH264;
  if (name == "vp9") return VideoCodec::kVp9;
  throw std::invalid_argument("unknown video codec '" + name + "' (auto, h264, vp9)");
}

bool VideoOptions::IsValid(std::string* why) const {
  if (!(fps > 0 && fps <= 1000)) return invalid(why, "video fps must be > 0 and <= 1000");
  if (!(gop_s > 0 && gop_s <= 3600))
    return invalid(why, "video keyframe interval (gop) must be > 0 and <= 3600 s");
  if (codec == VideoCodec::kH264 && (crf < -1 || crf > 51))
    return invalid(why, "crf for h264 must be 0..51 (or -1: the default, 20)");
  if (crf < -1 || crf > 63)
    return invalid(why, "crf must be 0..51 for h264, 0..63 for vp9 (or -1: the default)");
  if (int(preset) < 0 || int(preset) >= int(std::size(kPresets))) return invalid(why, "unknown video preset");
  if (threads < 0 || threads > 256) return invalid(why, "video encoder threads must be 0..256");
  return true;
}

bool is_video_path(const fs::path& path) { return !muxer_for(lower_extension(path)).empty(); }

VideoCodec resolve_video_codec(const fs::path& path, VideoCodec codec) {
  const std::string ext = lower_extension(path);
  if (muxer_for(ext).empty())
    throw std::invalid_argument("'" + path.string() +
                                "': not a video file omma writes (.mp4 .m4v .mov .mkv .webm .avi)");
  if (codec == VideoCodec::kAuto) return ext == ".webm" ? VideoCodec::kVp9 : VideoCodec::kH264;
  if (codec == VideoCodec::kH264 && ext == ".webm")
    throw std::invalid_argument("'" + path.string() +
                                "': WebM holds VP9, not H.264 (use .mp4 or .mkv for h264)");
  if (codec == VideoCodec::kVp9 && (ext == ".mov" || ext == ".avi"))
    throw std::invalid_argument("'" + path.string() + "': use .webm, .mkv or .mp4 for vp9");
  return codec;
}

fs::path partial_path(const fs::path& path) {
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  // (fmt: GCC 12 -Wrestrict false positive on "." + string)
  return dir / fmt::format(".{}.partial{}", path.stem().string(), path.extension().string());
}

struct VideoWriter::Impl {
  fs::path path, tmp;
  cv::Size size;
  VideoOptions opt;
  VideoCodec codec = VideoCodec::kH264;
  std::optional<Projection> projection;
  AVFormatContext* fmt = nullptr;
  AVCodecContext* enc = nullptr;
  AVStream* st = nullptr;
  SwsContext* sws = nullptr;
  int sws_type = -1;  // the cv::Mat type sws converts from
  AVFrame* frame = nullptr;
  AVPacket* pkt = nullptr;
  long frames = 0;
  int crf = 0;
  bool active = false;  // the temporary file is being written

  ~Impl() { release(); }

  // Frees every FFmpeg object (closing the file without its index).
  void release() {
    if (fmt) {
      if (fmt->pb) avio_closep(&fmt->pb);
      avformat_free_context(fmt);
      fmt = nullptr;
    }
    avcodec_free_context(&enc);
    av_frame_free(&frame);
    av_packet_free(&pkt);
    sws_freeContext(sws);
    sws = nullptr;
  }
  void remove_tmp() {
    release();
    std::error_code ec;
    fs::remove(tmp, ec);
    active = false;
  }
  // Removes the temporary file and throws IoError with `message`.
  [[noreturn]] void fail(const std::string& message) {
    remove_tmp();
    throw IoError("video " + path.string() + " could not be written: " + message);
  }
  // Writes every packet the encoder has ready.
  void drain() {
    for (;;) {
      const int e = avcodec_receive_packet(enc, pkt);
      if (e == AVERROR(EAGAIN) || e == AVERROR_EOF) return;
      if (e < 0) fail("encoder: " + av_error(e));
      av_packet_rescale_ts(pkt, enc->time_base, st->time_base);
      pkt->stream_index = st->index;
      if (const int w = av_interleaved_write_frame(fmt, pkt); w < 0) fail(av_error(w) + " (disk full?)");
    }
  }
};

VideoWriter::VideoWriter(const fs::path& path, cv::Size size, const VideoOptions& options,
                         std::optional<Projection> projection)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  if (std::string why; !options.IsValid(&why)) throw std::invalid_argument(why);
  m.path = path;
  m.size = size;
  m.opt = options;
  m.projection = projection;
  m.codec = resolve_video_codec(path, options.codec);
  if (options.codec == VideoCodec::kAuto && m.codec == VideoCodec::kH264 && options.crf > 51)
    throw std::invalid_argument("crf for h264 must be 0..51");
  if (size.width < 2 || size.height < 2 || size.width % 2 || size.height % 2 || size.width > 16384 ||
      size.height > 16384)
    throw std::invalid_argument(
        fmt::format("video '{}': {}x{} frames: 4:2:0 video needs an even width and "
                    "height, 2..16384 pixels",
                    path.string(), size.width, size.height));
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw IoError("cannot write video " + path.string() + ": folder " + dir.string() + " does not exist");
  m.tmp = partial_path(path);
  remove_leftover(m.tmp, path);
  quiet_ffmpeg_log();
  const std::string what = "cannot write video '" + path.string() + "': ";
  const std::string ext = lower_extension(path);
  if (const int e = avformat_alloc_output_context2(&m.fmt, nullptr, muxer_for(ext).c_str(), m.tmp.c_str());
      e < 0)
    throw IoError(what + av_error(e));
  const bool h264 = m.codec == VideoCodec::kH264;
  const char* encoder_name = h264 ? "libx264" : "libvpx-vp9";
  const AVCodec* encoder = avcodec_find_encoder_by_name(encoder_name);
  if (!encoder) {
    m.release();
    throw IoError(what + "FFmpeg's libavcodec has no " + encoder_name + " encoder");
  }
  m.enc = avcodec_alloc_context3(encoder);
  m.frame = av_frame_alloc();
  m.pkt = av_packet_alloc();
  if (!m.enc || !m.frame || !m.pkt) {
    m.release();
    throw std::bad_alloc();
  }
  const AVRational rate = av_d2q(options.fps, 1000000);
  m.enc->width = size.width;
  m.enc->height = size.height;
  m.enc->pix_fmt = options.ten_bit ? AV_PIX_FMT_YUV420P10LE : AV_PIX_FMT_YUV420P;
  m.enc->time_base = av_inv_q(rate);
  m.enc->framerate = rate;
  m.enc->gop_size = std::max(1, int(std::lround(options.gop_s * options.fps)));
  m.enc->color_range = AVCOL_RANGE_MPEG;
  m.enc->colorspace = AVCOL_SPC_BT709;
  m.enc->color_primaries = AVCOL_PRI_BT709;
  m.enc->color_trc = AVCOL_TRC_BT709;
  m.enc->thread_count = options.threads;
  if (m.fmt->oformat->flags & AVFMT_GLOBALHEADER) m.enc->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
  m.crf = options.crf >= 0 ? options.crf : (h264 ? 20 : 31);
  AVDictionary* enc_opts = nullptr;
  av_dict_set_int(&enc_opts, "crf", m.crf, 0);
  const int speed = int(options.preset);  // 0 ultrafast .. 8 veryslow
  if (h264) {
    av_dict_set(&enc_opts, "preset", kPresets[speed], 0);
  } else {
    m.enc->bit_rate = 0;  // constant quality
    av_dict_set(&enc_opts, "deadline", speed <= 3 ? "realtime" : "good", 0);
    av_dict_set_int(&enc_opts, "cpu-used", 8 - speed, 0);
    av_dict_set_int(&enc_opts, "row-mt", 1, 0);
  }
  const int opened = avcodec_open2(m.enc, encoder, &enc_opts);
  av_dict_free(&enc_opts);
  if (opened < 0) {
    m.release();
    throw IoError(what + encoder_name + " did not open: " + av_error(opened));
  }
  m.st = avformat_new_stream(m.fmt, nullptr);
  if (!m.st || avcodec_parameters_from_context(m.st->codecpar, m.enc) < 0) {
    m.release();
    throw std::bad_alloc();
  }
  m.st->time_base = m.enc->time_base;
  m.st->avg_frame_rate = rate;
  // Matroska/WebM: the Projection element from the stream's spherical side data (MP4/MOV get their
  // V1 and V2 boxes at close()).
  if (projection && is_matroska_path(path)) {
    AVSphericalMapping* s = nullptr;
    size_t bytes = 0;
    try {
      std::tie(s, bytes) = spherical_side_data(PanoGrid{*projection, size.width, size.height});
    } catch (...) {
      m.release();
      throw;
    }
    if (av_stream_add_side_data(m.st, AV_PKT_DATA_SPHERICAL, reinterpret_cast<uint8_t*>(s), bytes) < 0) {
      av_free(s);
      m.release();
      throw std::bad_alloc();
    }
  }
  m.frame->format = m.enc->pix_fmt;
  m.frame->width = size.width;
  m.frame->height = size.height;
  if (av_frame_get_buffer(m.frame, 0) < 0) {
    m.release();
    throw std::bad_alloc();
  }
  if (const int e = avio_open(&m.fmt->pb, m.tmp.c_str(), AVIO_FLAG_WRITE); e < 0) {
    m.release();
    throw IoError(what + av_error(e) + " (folder writable?)");
  }
  m.active = true;
  AVDictionary* mux_opts = nullptr;
  if (is_isobmff_path(path)) av_dict_set(&mux_opts, "movflags", "+faststart", 0);
  const int header = avformat_write_header(m.fmt, &mux_opts);
  av_dict_free(&mux_opts);
  if (header < 0) m.fail(av_error(header));
}

VideoWriter::~VideoWriter() { abort(); }

void VideoWriter::write(const cv::Mat& image) {
  Impl& m = *impl_;
  if (!m.active) throw IoError("video '" + m.path.string() + "' is closed");
  if (image.size() != m.size)
    throw std::invalid_argument(fmt::format("video '{}': a {}x{} frame in a {}x{} video", m.path.string(),
                                            image.cols, image.rows, m.size.width, m.size.height));
  const int type = image.type();
  if (type != CV_8UC3 && type != CV_16UC3 && type != CV_8UC1)
    throw std::invalid_argument("video '" + m.path.string() +
                                "': frames must be 8- or 16-bit BGR or 8-bit grey");
  if (type != m.sws_type) {
    sws_freeContext(m.sws);
    const AVPixelFormat src = type == CV_8UC3    ? AV_PIX_FMT_BGR24
                              : type == CV_16UC3 ? AV_PIX_FMT_BGR48
                                                 : AV_PIX_FMT_GRAY8;
    m.sws = sws_getContext(m.size.width, m.size.height, src, m.size.width, m.size.height, m.enc->pix_fmt,
                           SWS_BICUBIC | SWS_ACCURATE_RND | SWS_FULL_CHR_H_INT, nullptr, nullptr, nullptr);
    if (!m.sws) m.fail("no pixel format conversion");
    // RGB full range in, BT.709 limited range out.
    sws_setColorspaceDetails(m.sws, sws_getCoefficients(SWS_CS_ITU709), 1, sws_getCoefficients(SWS_CS_ITU709),
                             0, 0, 1 << 16, 1 << 16);
    m.sws_type = type;
  }
  if (const int e = av_frame_make_writable(m.frame); e < 0) m.fail(av_error(e));
  const uint8_t* src[1] = {image.data};
  const int stride[1] = {int(image.step[0])};
  sws_scale(m.sws, src, stride, 0, m.size.height, m.frame->data, m.frame->linesize);
  m.frame->pts = m.frames;
  if (const int e = avcodec_send_frame(m.enc, m.frame); e < 0) m.fail("encoder: " + av_error(e));
  ++m.frames;
  m.drain();
}

VideoSummary VideoWriter::close() {
  Impl& m = *impl_;
  if (!m.active) throw IoError("video '" + m.path.string() + "' is closed");
  if (m.frames == 0) {
    m.remove_tmp();
    throw IoError("no frames: video '" + m.path.string() + "' not written");
  }
  if (const int e = avcodec_send_frame(m.enc, nullptr); e < 0) m.fail("encoder: " + av_error(e));
  m.drain();
  if (const int e = av_write_trailer(m.fmt); e < 0) m.fail(av_error(e) + " (disk full?)");
  if (const int e = avio_closep(&m.fmt->pb); e < 0) m.fail(av_error(e) + " (disk full?)");
  VideoSummary s;
  s.path = m.path;
  s.codec = to_string(m.codec);
  s.pix_fmt = av_get_pix_fmt_name(m.enc->pix_fmt);
  s.width = m.size.width;
  s.height = m.size.height;
  s.frames = m.frames;
  s.fps = m.opt.fps;
  s.crf = m.crf;
  m.release();
  if (m.projection) {
    s.spherical = true;
    if (is_isobmff_path(m.path)) {
      // V1 and V2 boxes; the rewrite needs room for a second copy: if it fails, the video is kept
      // untagged (a warning says so).
      try {
        set_spherical_video_metadata(m.tmp, PanoGrid{*m.projection, m.size.width, m.size.height});
      } catch (const IoError& e) {
        spdlog::warn("{} (the video is kept without 360-degree metadata)", e.what());
        s.spherical = false;
      }
    } else if (!is_matroska_path(m.path)) {
      s.spherical = false;  // AVI: no spherical metadata
    }
  }
  std::error_code ec;
  fs::rename(m.tmp, m.path, ec);
  if (ec) {
    m.remove_tmp();
    throw IoError("cannot move video into place at " + m.path.string() + ": " + ec.message());
  }
  m.active = false;
  return s;
}

void VideoWriter::abort() {
  if (impl_ && impl_->active) impl_->remove_tmp();
  if (impl_) impl_->release();
}

long VideoWriter::frames() const { return impl_->frames; }
const fs::path& VideoWriter::path() const { return impl_->path; }

}  // namespace omma::io
