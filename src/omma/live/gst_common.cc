// GStreamer's one-time initialisation and what the gst: sources and rtsp:// / srt:// sinks share
// (gst.h).
#include <mutex>
#include <stdexcept>

#include "omma/live/gst.h"

#if OMMA_HAVE_GSTREAMER
#include <gst/gst.h>
#endif

namespace omma::live {

bool gstreamer_built() { return OMMA_HAVE_GSTREAMER; }

void init_gstreamer() {
#if OMMA_HAVE_GSTREAMER
  static std::once_flag once;
  static std::string error;
  std::call_once(once, [] {
    GError* err = nullptr;
    if (!gst_init_check(nullptr, nullptr, &err)) {
      error = err ? err->message : "unknown error";
      if (err) g_error_free(err);
    }
  });
  if (!error.empty()) throw std::runtime_error("GStreamer cannot be initialised: " + error);
#else
  throw std::runtime_error(
      "this omma was built without GStreamer (install its development files, e.g. with "
      "scripts/install-deps.sh, and build again)");
#endif
}

}  // namespace omma::live
