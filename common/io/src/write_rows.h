#pragma once
// Checks shared by the io writers (internal header).
#include <filesystem>
#include <vector>

#include <fmt/format.h>

#include "mrvs/core/status.h"

namespace mrvs::io {

/// Error unless times strictly increase and every value is finite.
template <typename Row, typename AllFinite>
Status check_rows_to_write(const std::filesystem::path& path, const std::vector<Row>& rows,
                           AllFinite all_finite) {
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!all_finite(rows[i])) {
      return absl::InvalidArgumentError(fmt::format(
          "cannot write {}: entry {} (t = {} ns) has a non-finite value; fix the data before writing",
          path.string(), i, rows[i].t_ns));
    }
    if (i > 0 && rows[i].t_ns <= rows[i - 1].t_ns) {
      return absl::InvalidArgumentError(
          fmt::format("cannot write {}: entry {} has t = {} ns, not after entry {} (t = {} ns); times must "
                      "strictly increase: sort the data and remove duplicates before writing",
                      path.string(), i, rows[i].t_ns, i - 1, rows[i - 1].t_ns));
    }
  }
  return absl::OkStatus();
}

}  // namespace mrvs::io
