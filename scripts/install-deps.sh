#!/usr/bin/env bash
# Installs the Debian packages omma needs, only those missing. Uses sudo when not root.
# --test also installs what only the tests use: Chromium, for the live-view test in a headless browser;
# Verilator, Yosys and Icarus Verilog for the RTL co-simulation and lint (hw/rtl, CMake OMMA_RTL);
# pytest for the Python bindings; exiftool and ffprobe (ffmpeg), which read the 360-degree metadata;
# xxhash (xxhsum: the MPI tests check the manifests' checksums with the standard tool); Tesseract OCR,
# the outside judge that panoramas and camera frames show text the right way round; clang-format,
# which the tests run first (scripts/format.sh --check).
# Then the live view's npm packages (web/package-lock.json: the Pannellum viewer, embedded in the
# binary at build time, and playwright-core, which drives Chromium in the viewer's test) with npm ci.
set -euo pipefail
pkgs=(cmake g++ ninja-build ccache pkg-config libopencv-dev libeigen3-dev libceres-dev libtbb-dev
      libcli11-dev nlohmann-json3-dev libspdlog-dev libfmt-dev libgtest-dev libgmock-dev
      libbenchmark-dev hugin-tools libcpp-httplib-dev zlib1g-dev libtiff-dev libhdf5-dev python3-dev pybind11-dev
      python3-numpy libxxhash-dev libopenmpi-dev openmpi-bin help2man)
pkgs+=(libavcodec-dev libavformat-dev libavutil-dev libswscale-dev)  # video files (src/omma/io/video_writer.h)
# GStreamer: gst: sources, rtsp:// and srt:// sinks (src/omma/live/gst.h) and the plugin (gst/): the
# development files, gst-rtsp-server, and the plugins they run (x264enc: ugly; srtsink, mpegtsmux: bad;
# avdec_h264: libav), gst-launch-1.0 and gst-inspect-1.0 (tools).
pkgs+=(libgstreamer1.0-dev libgstreamer-plugins-base1.0-dev libgstrtspserver-1.0-dev gstreamer1.0-tools
       gstreamer1.0-plugins-base gstreamer1.0-plugins-good gstreamer1.0-plugins-bad gstreamer1.0-plugins-ugly
       gstreamer1.0-libav)
[ "${1:-}" = "--test" ] && pkgs+=(chromium verilator yosys iverilog python3-pytest libimage-exiftool-perl ffmpeg xxhash
                    tesseract-ocr tesseract-ocr-eng clang-format python3-mypy hdf5-tools)
[ "${1:-}" = "--test" ] && pkgs+=(python3-h5py)  # reads recordings back (tests/cli/recording_cli_test.cc)
# Real photographs with ground truth (opencv-doc: a stereo pair with a chessboard, Middlebury Aloe, leuven,
# aero, Graffiti; src/omma/testing/real_data.h) and the peers that stitch and calibrate them beside omma:
# COLMAP and Hugin (hugin-tools, above).
[ "${1:-}" = "--test" ] && pkgs+=(opencv-doc colmap)
command -v npm >/dev/null || pkgs+=(nodejs npm)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "omma: installing Debian packages: ${missing[*]}" >&2
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi

# npm ci only when web/node_modules does not match the lock file (a copy of it marks what was installed).
web="$(dirname "$0")/../web"
if ! cmp -s "$web/package-lock.json" "$web/node_modules/.omma-lock" 2>/dev/null; then
  echo "omma: installing the live view's npm packages (web/package-lock.json)" >&2
  (cd "$web" && npm ci --no-audit --no-fund --loglevel=error >&2)
  cp "$web/package-lock.json" "$web/node_modules/.omma-lock"
fi
