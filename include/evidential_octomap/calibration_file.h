// The parameter file `evidential_octomap calibrate` writes: `key: value` lines and # comments,
// which the node loads as private parameters (rosparam), `map`/`eval --calibration FILE` and
// Python's read_calibration read.
#pragma once

#include <string>

namespace evidential_octomap {

// The read-out cap of a calibration file; throws std::runtime_error naming the file and the line
// when it cannot be read, holds a key other than evidence_cap, or a cap that is neither -1
// (SemanticConfig::kAdaptiveCap: the fit was not better than the adaptive cap) nor a finite
// number >= 0.
double readCalibrationCap(const std::string& path);

}  // namespace evidential_octomap
