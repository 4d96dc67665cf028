// GStreamer helpers that the gst: sources and the rtsp:// and srt:// sinks share (and `omma bench
// --stream`, bench/stream_bench.h): a pipeline from a gst-launch description, the text of an error
// message. Only with OMMA_HAVE_GSTREAMER (this header includes GStreamer's); gst.h is the contract
// without GStreamer types.
#pragma once

#if OMMA_HAVE_GSTREAMER
#include <string>

#include <gst/gst.h>

namespace omma::live {

// gst_parse_launch_full(description) with GST_PARSE_FLAG_FATAL_ERRORS: the pipeline (a full
// reference, the parser's floating one sunk: gst_object_unref it), or nullptr with *error set to
// GStreamer's message (e.g. 'no element "foo"').
GstElement* parse_pipeline(const std::string& description, std::string* error);

// The text of an ERROR or WARNING message: its GError's message ("unknown error" without one);
// *debug, if given, gets the message's debug string ("" without one).
std::string message_text(GstMessage* msg, std::string* debug = nullptr);

}  // namespace omma::live
#endif
