// GStreamer's one-time initialisation and what the gst: sources and rtsp:// / srt:// sinks share
// (gst.h).
#include <mutex>
#include <stdexcept>

#include "omma/live/gst.h"
#include "omma/live/gst_util.h"

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

#if OMMA_HAVE_GSTREAMER
GstElement* parse_pipeline(const std::string& description, std::string* error) {
  GError* err = nullptr;
  GstElement* p = gst_parse_launch_full(description.c_str(), nullptr, GST_PARSE_FLAG_FATAL_ERRORS, &err);
  if (!p || err) {
    *error = err ? err->message : "unknown error";
    if (err) g_error_free(err);
    if (p) gst_object_unref(p);
    return nullptr;
  }
  gst_object_ref_sink(p);  // the parser's reference is floating
  return p;
}

std::string message_text(GstMessage* msg, std::string* debug) {
  GError* err = nullptr;
  gchar* dbg = nullptr;
  if (GST_MESSAGE_TYPE(msg) == GST_MESSAGE_ERROR)
    gst_message_parse_error(msg, &err, &dbg);
  else if (GST_MESSAGE_TYPE(msg) == GST_MESSAGE_WARNING)
    gst_message_parse_warning(msg, &err, &dbg);
  std::string text = err ? err->message : "unknown error";
  if (debug) *debug = dbg ? dbg : "";
  if (err) g_error_free(err);
  g_free(dbg);
  return text;
}
#endif

}  // namespace omma::live
