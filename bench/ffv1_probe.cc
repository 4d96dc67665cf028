// Measures what FFV1 (lossless, FFmpeg's libavcodec) would cost for the recorder: encode speed and
// compression ratio of 12-bit RGGB mosaics, stored as gray12le (the whole mosaic) or as four
// half-size planes gbrap12le (G1, B, R, G2). Used to choose the container (docs/results/giga_bench.md);
// not part of the build: docs/results/giga_bench.sh compiles it with g++ and pkg-config.
//   ffv1_probe RAW.png [RAW.png ...]   (16-bit single-channel mosaics, 12-bit values)
#include <chrono>
#include <cstdio>
#include <cstring>
#include <vector>

#include <opencv2/imgcodecs.hpp>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/opt.h>
}

static double encode(const std::vector<cv::Mat>& raws, AVPixelFormat fmt, int threads, size_t* out_bytes) {
  const int w = fmt == AV_PIX_FMT_GRAY12LE ? raws[0].cols : raws[0].cols / 2;
  const int h = fmt == AV_PIX_FMT_GRAY12LE ? raws[0].rows : raws[0].rows / 2;
  const AVCodec* codec = avcodec_find_encoder(AV_CODEC_ID_FFV1);
  AVCodecContext* ctx = avcodec_alloc_context3(codec);
  ctx->width = w;
  ctx->height = h;
  ctx->pix_fmt = fmt;
  ctx->time_base = {1, 30};
  ctx->thread_count = threads;
  av_opt_set_int(ctx->priv_data, "level", 3, 0);
  av_opt_set_int(ctx->priv_data, "slices", 4 * threads, 0);
  av_opt_set_int(ctx->priv_data, "slicecrc", 1, 0);
  if (avcodec_open2(ctx, codec, nullptr) < 0) return -1;
  AVFrame* f = av_frame_alloc();
  f->format = fmt;
  f->width = w;
  f->height = h;
  av_frame_get_buffer(f, 0);
  AVPacket* pkt = av_packet_alloc();
  *out_bytes = 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (size_t i = 0; i < raws.size(); ++i) {
    const cv::Mat& m = raws[i];
    av_frame_make_writable(f);
    if (fmt == AV_PIX_FMT_GRAY12LE) {
      for (int r = 0; r < h; ++r) std::memcpy(f->data[0] + r * f->linesize[0], m.ptr(r), w * 2);
    } else {  // planes G, B, R, A <- (0,1), (1,1), (0,0), (1,0)
      const int src[4][2] = {{0, 1}, {1, 1}, {0, 0}, {1, 0}};
      for (int p = 0; p < 4; ++p)
        for (int r = 0; r < h; ++r) {
          uint16_t* d = reinterpret_cast<uint16_t*>(f->data[p] + r * f->linesize[p]);
          const uint16_t* s = m.ptr<uint16_t>(2 * r + src[p][0]);
          for (int c = 0; c < w; ++c) d[c] = s[2 * c + src[p][1]];
        }
    }
    f->pts = i;
    avcodec_send_frame(ctx, f);
    while (avcodec_receive_packet(ctx, pkt) == 0) {
      *out_bytes += pkt->size;
      av_packet_unref(pkt);
    }
  }
  avcodec_send_frame(ctx, nullptr);
  while (avcodec_receive_packet(ctx, pkt) == 0) {
    *out_bytes += pkt->size;
    av_packet_unref(pkt);
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  av_packet_free(&pkt);
  av_frame_free(&f);
  avcodec_free_context(&ctx);
  return s;
}

int main(int argc, char** argv) {
  std::vector<cv::Mat> raws;
  for (int i = 1; i < argc; ++i) raws.push_back(cv::imread(argv[i], cv::IMREAD_UNCHANGED));
  if (raws.empty() || raws[0].type() != CV_16UC1) {
    std::fprintf(stderr, "usage: ffv1_probe RAW16.png...\n");
    return 1;
  }
  const double raw_bytes = double(raws.size()) * raws[0].total() * 2;  // as the recorder stores them
  for (AVPixelFormat fmt : {AV_PIX_FMT_GRAY12LE, AV_PIX_FMT_GBRAP12LE})
    for (int threads : {1, 2}) {
      size_t bytes = 0;
      const double s = encode(raws, fmt, threads, &bytes);
      std::printf(
          "{\"codec\": \"ffv1\", \"pix_fmt\": \"%s\", \"threads\": %d, \"frames\": %zu, \"input_mb_per_s\": "
          "%.1f, "
          "\"ratio_vs_16bit\": %.3f, \"ratio_vs_12bit_packed\": %.3f}\n",
          fmt == AV_PIX_FMT_GRAY12LE ? "gray12le" : "gbrap12le", threads, raws.size(), raw_bytes / 1e6 / s,
          raw_bytes / bytes, raw_bytes * 0.75 / bytes);
    }
  return 0;
}
