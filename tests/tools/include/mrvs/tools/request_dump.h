#pragma once
// Localisation requests kept as text for the measurement tools (localise_probe --dump writes
// them, --replay and localise_compare read them): one file req_<seq>.txt per request with
//   "TRUE" and "ANSWER" 4x4 rows of T_map_odom (the simulator's truth, the cloud's answer),
//   "ANCHOR x y z" and "GRAVITY x y z" (odometry frame), "PRIOR x y z radius" (map frame, when
//   the request had one), "P x y z" per point (relative to the anchor) and "V x y z count" per
//   viewpoint.
#include <optional>
#include <string>
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/geometry/se3.h"
#include "mrvs/localisation/types.h"

namespace mrvs::tools {

struct DumpedRequest {
  localisation::Request request;
  SE3d truth;   ///< true T_map_odom
  SE3d answer;  ///< the cloud's T_map_odom when it was dumped
};

/// Writes DIR/req_<seq>.txt (DIR is created); error naming the file when it cannot.
Status write_request_dump(const std::string& dir, const localisation::Request& request, const SE3d& answer,
                          const SE3d& truth);

/// Reads one dump; error naming the file and what is missing.
StatusOr<DumpedRequest> read_request_dump(const std::string& path);

/// The req_*.txt files under dir (recursively), sorted.
std::vector<std::string> request_dump_files(const std::string& dir);

}  // namespace mrvs::tools
