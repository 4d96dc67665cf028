// Loopback networking for tests that start a server (the live view's HTTP sink, `omma run --sink
// http:PORT`).
#pragma once

namespace omma::testing {

// A loopback (127.0.0.1) TCP port that was free a moment ago; 0 if none could be found. Another
// process may take it meanwhile: callers retry with a fresh port when binding fails.
int free_port();

}  // namespace omma::testing
