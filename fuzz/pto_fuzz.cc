// libFuzzer target for the Hugin PTO importer (calib/pto.h): any text must either import as a
// valid rig or throw PtoError / RigError, without a crash, undefined behaviour or a hang. Image
// names resolve against a folder that does not exist, so no image is read. Build and run with
// fuzz/run.sh.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "omma/calib/pto.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const omma::calib::PtoImportSummary r = omma::calib::import_pto(text, "/nonexistent-omma-fuzz");
    r.rig.validate();  // what was imported is a valid rig
    if (r.rig.cameras.empty() || !std::isfinite(r.max_fit_px)) abort();
  } catch (const omma::calib::PtoError&) {
  } catch (const omma::RigError&) {
  }
  return 0;
}
