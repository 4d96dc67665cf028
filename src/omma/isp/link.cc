#include "omma/isp/link.h"

#include <algorithm>
#include <random>
#include <stdexcept>

namespace omma::isp {

void LinkConfig::validate() const {
  auto bad = [](const std::string& what) { throw std::invalid_argument("link config: " + what); };
  if (width < 1 || width > 16384) bad("width must be in 1..16384, got " + std::to_string(width));
  if (height < 1 || height > 16384) bad("height must be in 1..16384, got " + std::to_string(height));
  if (bits < 1 || bits > 16) bad("bits must be in 1..16, got " + std::to_string(bits));
  // A row is found by a run of >= chips_per_pp + 4 alternating chips (longer than anything inside
  // pixel data, at most 2*(bits+1)); the gap must leave a margin of 8 chips over that.
  if (row_gap_pp < 1 || row_gap_pp > 100000 || (row_gap_pp - 1) * chips_per_pp() < 12)
    bad("row gap of " + std::to_string(row_gap_pp) + " PP is too short to find rows");
  if (eof_pp < 1 || eof_pp > 100000) bad("end-of-frame marker must be 1..100000 PP");
  if (config_pp < 0 || config_pp > 1000000) bad("configuration window must be 0..1000000 PP");
  if (resync_pp < 0 || resync_pp > 1000000) bad("resynchronisation must be 0..1000000 PP");
}

void ChipStream::push(bool c) {
  if ((chips & 7) == 0) bytes.push_back(0);
  if (c) bytes.back() |= uint8_t(0x80u >> (chips & 7));
  ++chips;
}

namespace {

// One data bit XOR the clock (high in the first half): chips (!b, b).
void push_bit(ChipStream& s, bool b) {
  s.push(!b);
  s.push(b);
}

}  // namespace

ChipStream encode_link(const std::vector<LinkFrame>& frames, const LinkConfig& cfg) {
  cfg.validate();
  ChipStream s;
  s.bytes.reserve(frames.size() * (cfg.frame_chips() / 8 + 1));
  const uint32_t limit = 1u << cfg.bits;
  for (const LinkFrame& f : frames) {
    if (f.width != cfg.width || f.height != cfg.height ||
        f.pixels.size() != size_t(f.width) * size_t(f.height))
      throw std::invalid_argument("link: frame is " + std::to_string(f.width) + "x" +
                                  std::to_string(f.height) + ", the link carries " +
                                  std::to_string(cfg.width) + "x" + std::to_string(cfg.height));
    for (int r = 0; r < cfg.height; ++r) {
      for (int k = 0; k < cfg.row_gap_pp * cfg.clocks_per_pp(); ++k) push_bit(s, false);  // 1.1
      for (int c = 0; c < cfg.width; ++c) {                                               // 1.2
        const uint32_t v = f.pixels[size_t(r) * cfg.width + c];
        if (v >= limit)
          throw std::invalid_argument("link: pixel value " + std::to_string(v) + " at (" + std::to_string(c) +
                                      ", " + std::to_string(r) + ") does not fit in " +
                                      std::to_string(cfg.bits) + " bits");
        push_bit(s, true);  // start bit
        for (int b = cfg.bits - 1; b >= 0; --b) push_bit(s, (v >> b) & 1u);
        push_bit(s, false);  // stop bit
      }
    }
    for (int k = 0; k < (cfg.eof_pp + cfg.config_pp) * cfg.chips_per_pp(); ++k) s.push(false);  // 251, 252
    for (int k = 0; k < cfg.resync_pp * cfg.clocks_per_pp(); ++k) push_bit(s, false);           // 253
  }
  return s;
}

ChipStream impair_link(const ChipStream& in, double flip_rate, double drop_rate, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ChipStream out;
  out.bytes.reserve(in.bytes.size());
  for (size_t i = 0; i < in.chips; ++i) {
    bool c = in.chip(i);
    if (flip_rate > 0 && u(rng) < flip_rate) c = !c;
    if (drop_rate > 0 && u(rng) < drop_rate) continue;
    out.push(c);
  }
  return out;
}

namespace {

// floor(a / b) for b > 0.
int64_t floor_div(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

class Decoder {
 public:
  Decoder(const uint8_t* data, size_t size, const LinkConfig& cfg,
          const std::function<void(const LinkFrame&)>& on_frame)
      : d_(data), n_(size * 8), cfg_(cfg), on_frame_(on_frame) {
    cpp_ = size_t(cfg.chips_per_pp());
    row_thresh_ = cpp_ + 4;
    const_thresh_ = std::max<size_t>(6, size_t(cfg.eof_pp) * cpp_ / 2);
    long_enabled_ = cfg.resync_pp >= 4;
    long_thresh_ = size_t(cfg.row_gap_pp + cfg.resync_pp / 2) * cpp_;
    row_chips_ = cfg.row_chips();
    anchor_pos_ = int64_t(size_t(cfg.row_gap_pp) * cpp_);
    anchor_idx_ = 0;
    stats_.bytes = size;
    row_.resize(size_t(cfg.width));
  }

  LinkSummary run() {
    size_t i = 1;
    size_t alt = 1, cst = 1;  // alternating / constant run lengths ending at chip i-1
    bool in_const = false;    // inside a constant run already counted as a frame boundary
    while (i < n_) {
      const bool c = chip(i), prev = chip(i - 1);
      if (c != prev) {
        if (in_const) {
          // End of the end-of-frame + configuration run: row 0 follows the resync pattern.
          in_const = false;
          anchor_pos_ = int64_t(i) + int64_t(size_t(cfg_.resync_pp + cfg_.row_gap_pp) * cpp_);
          anchor_idx_ = 0;
          synced_ = true;
        }
        ++alt;
        cst = 1;
        ++i;
        continue;
      }
      // c == prev: the alternation breaks here.
      ++cst;
      if (!in_const && cst >= const_thresh_) {
        in_const = true;
        finish_frame();
      }
      if (!c && alt >= row_thresh_ && i + 1 < n_ && chip(i + 1)) {
        // Start bit (chips 0,1) at i after a long run of zeros XOR clock: a row.
        const size_t next = take_row(i, alt);
        i = std::max(next, i + 1);
        alt = run_back_alternating(i);
        cst = run_back_constant(i);
        continue;
      }
      alt = 1;
      ++i;
    }
    finish_frame();
    return stats_;
  }

 private:
  bool chip(size_t i) const { return (d_[i >> 3] >> (7 - (i & 7))) & 1; }

  // Lengths of the runs ending at chip i-1 (bounded: only thresholds matter).
  size_t run_back_alternating(size_t i) const {
    if (i == 0) return 0;
    const size_t cap = std::max(long_thresh_, row_thresh_) + 1;
    size_t len = 1;
    while (len < cap && i - 1 >= len && chip(i - 1 - len) != chip(i - len)) ++len;
    return len;
  }
  size_t run_back_constant(size_t i) const {
    if (i == 0) return 0;
    const size_t cap = const_thresh_ + 1;
    size_t len = 1;
    while (len < cap && i - 1 >= len && chip(i - 1 - len) == chip(i - len)) ++len;
    return len;
  }

  // Clears the frame. Only rows stored since the last reset are touched, so that inputs full of
  // frame boundaries cost time in proportion to their length, not to frames x frame size.
  void reset_frame() {
    for (int r : stored_rows_) {
      std::fill_n(frame_.pixels.begin() + long(r) * cfg_.width, cfg_.width, uint16_t(0));
      frame_.row_ok[size_t(r)] = 0;
    }
    stored_rows_.clear();
    rows_seen_ = 0;
  }

  void finish_frame() {
    if (rows_seen_ > 0) {
      const long ok = long(stored_rows_.size());
      if (ok > 0) {
        ++stats_.frames;
        stats_.rows_ok += ok;
        stats_.rows_damaged += cfg_.height - ok;
        on_frame_(frame_);
      }
    }
    reset_frame();
  }

  // Decodes the row whose start bit begins at chip q; `run` is the alternating run before it.
  // Returns where scanning continues: the row's end if intact, else the first bad pixel.
  size_t take_row(size_t q, size_t run) {
    if (long_enabled_ && run >= long_thresh_) {  // the resynchronisation pattern: a new frame
      finish_frame();
      anchor_pos_ = int64_t(q);
      anchor_idx_ = 0;
      synced_ = true;
    }
    // Row indices come from timing relative to a known row: the distance d to it in chips, rounded
    // to whole row periods (round half up, exact integers: hw/rtl/frontend/link_deser.sv makes the
    // same decision with a counter).
    const int64_t d = int64_t(q) - anchor_pos_, rp = int64_t(row_chips_);
    const int64_t slot = floor_div(2 * d + rp, 2 * rp);  // floor(d / rp + 1/2)
    // Until the stream is synchronised (its first row sits in a row slot counted from the stream
    // start, or a frame boundary / resynchronisation run has been seen), rows are skipped: a
    // capture that starts mid-frame must not misplace them.
    if (!synced_ && !any_row_) {  // the first row: in a row slot from the stream start (+-1 PP)?
      const int64_t off = d - slot * rp;
      if (off <= int64_t(cpp_) && -off <= int64_t(cpp_)) synced_ = true;
    }
    any_row_ = true;
    const int64_t idx_d = int64_t(anchor_idx_) + slot;
    const bool in_frame = synced_ && idx_d >= 0 && idx_d < int64_t(cfg_.height);
    const int idx = in_frame ? int(idx_d) : -1;

    const size_t clocks = size_t(cfg_.clocks_per_pp());
    size_t fail = 0;
    bool ok = true;
    for (int k = 0; k < cfg_.width && ok; ++k) {
      const size_t base = q + size_t(k) * cpp_;
      if (base + cpp_ > n_) {
        ok = false;
        fail = base;
        break;
      }
      uint32_t word = 0;
      for (size_t b = 0; b < clocks; ++b) {
        const bool a = chip(base + 2 * b), v = chip(base + 2 * b + 1);
        if (a == v) {  // no transition inside the bit: a flipped or lost sample
          ok = false;
          break;
        }
        word = (word << 1) | uint32_t(v);
      }
      // start bit 1 (MSB of the word), stop bit 0 (LSB)
      if (ok && (((word >> (clocks - 1)) & 1u) != 1u || (word & 1u) != 0u)) ok = false;
      if (!ok) {
        fail = base;
        break;
      }
      row_[size_t(k)] = uint16_t((word >> 1) & ((1u << cfg_.bits) - 1));
    }
    if (idx >= 0) {
      ++rows_seen_;
      if (ok) {                       // damaged rows are not stored: they stay 0
        if (frame_.pixels.empty()) {  // allocated at the first intact row
          frame_.width = cfg_.width;
          frame_.height = cfg_.height;
          frame_.pixels.assign(size_t(cfg_.width) * cfg_.height, 0);
          frame_.row_ok.assign(size_t(cfg_.height), 0);
        }
        std::copy(row_.begin(), row_.end(), frame_.pixels.begin() + long(idx) * cfg_.width);
        if (!frame_.row_ok[size_t(idx)]) stored_rows_.push_back(idx);
        frame_.row_ok[size_t(idx)] = 1;
        anchor_pos_ = int64_t(q);
        anchor_idx_ = idx;
      }
    }
    return ok ? q + size_t(cfg_.width) * cpp_ : fail;
  }

  const uint8_t* d_;
  size_t n_;
  LinkConfig cfg_;
  const std::function<void(const LinkFrame&)>& on_frame_;
  size_t cpp_, row_thresh_, const_thresh_, long_thresh_, row_chips_;
  bool long_enabled_;
  int64_t anchor_pos_;  // chip where the anchor row starts (or is expected)
  int anchor_idx_;
  LinkFrame frame_;
  std::vector<uint16_t> row_;     // the row being decoded
  std::vector<int> stored_rows_;  // rows of frame_ written since the last reset
  long rows_seen_ = 0;
  bool synced_ = false;   // row indices known (see take_row)
  bool any_row_ = false;  // a row start has been seen
  LinkSummary stats_;
};

}  // namespace

LinkSummary decode_link(const uint8_t* data, size_t size, const LinkConfig& config,
                        const std::function<void(const LinkFrame&)>& on_frame) {
  config.validate();
  if (size == 0 || data == nullptr) return LinkSummary{};
  Decoder dec(data, size, config, on_frame);
  return dec.run();
}

LinkSummary decode_link(const std::vector<uint8_t>& bytes, const LinkConfig& config,
                        const std::function<void(const LinkFrame&)>& on_frame) {
  return decode_link(bytes.data(), bytes.size(), config, on_frame);
}

int conceal_damaged_rows(LinkFrame& f) {
  int replaced = 0;
  const size_t w = size_t(f.width);
  for (int r = 0; r < f.height; ++r) {
    if (f.row_ok[size_t(r)]) continue;
    for (int d = 2; d < f.height; d += 2) {
      int src = -1;
      if (r - d >= 0 && f.row_ok[size_t(r - d)])
        src = r - d;
      else if (r + d < f.height && f.row_ok[size_t(r + d)])
        src = r + d;
      if (src >= 0) {
        std::copy_n(f.pixels.begin() + long(src * w), w, f.pixels.begin() + long(r * w));
        ++replaced;
        break;
      }
      if (r - d < 0 && r + d >= f.height) break;
    }
  }
  return replaced;
}

}  // namespace omma::isp
