// libFuzzer target for the rig file parser (core/rig.h): any bytes must either give a rig that
// passes validation or throw RigError (or a JSON parse error), without a crash, an out-of-bounds
// access, undefined behaviour or a hang. Build and run with fuzz/run.sh.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include <nlohmann/json.hpp>

#include "omma/core/limits.h"
#include "omma/core/rig.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const nlohmann::json j = nlohmann::json::parse(data, data + size, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return 0;
  try {
    const omma::Rig rig = omma::rig_from_json(j);
    rig.validate();  // what was accepted is valid, and survives a round trip
    if (rig.cameras.empty() || rig.cameras.size() > size_t(omma::kMaxCameras)) abort();
    const omma::Rig back = omma::rig_from_json(omma::rig_to_json(rig));
    if (back.cameras.size() != rig.cameras.size()) abort();
    for (const auto& c : rig.cameras) {
      const omma::CameraModel m = c.model();
      const auto px = m.project(c.frame.t);  // the optical axis lands on the principal point
      if (!px || !px->allFinite()) abort();
      if (!m.unproject(*px).allFinite()) abort();
    }
  } catch (const omma::RigError&) {
  } catch (const nlohmann::json::exception&) {
  }
  return 0;
}
