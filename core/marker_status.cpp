#include "core/marker_status.h"

namespace skinstream {

const char* to_string(MarkerStatus s) {
  switch (s) {
    case MarkerStatus::Measured: return "measured";
    case MarkerStatus::Relabelled: return "relabelled";
    case MarkerStatus::FilledPca: return "filled_pca";
    case MarkerStatus::FilledRigid: return "filled_rigid";
    case MarkerStatus::Held: return "held";
  }
  return "unknown";
}

}  // namespace skinstream
