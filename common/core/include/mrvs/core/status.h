#pragma once
// Error handling for library code: functions that can fail on bad input return
// mrvs::Status or mrvs::StatusOr<T> (absl). Library code never exits or aborts;
// the caller (a main() or a test) decides what to do with the error.
#include <absl/status/status.h>
#include <absl/status/statusor.h>

namespace mrvs {

using Status = absl::Status;
template <typename T>
using StatusOr = absl::StatusOr<T>;

}  // namespace mrvs

#define MRVS_STATUS_CONCAT_INNER_(a, b) a##b
#define MRVS_STATUS_CONCAT_(a, b) MRVS_STATUS_CONCAT_INNER_(a, b)

/// Returns from the current function if `expr` (a Status) is not OK.
#define MRVS_RETURN_IF_ERROR(expr)                       \
  do {                                                   \
    ::mrvs::Status mrvs_status_tmp_ = (expr);            \
    if (!mrvs_status_tmp_.ok()) return mrvs_status_tmp_; \
  } while (false)

/// `MRVS_ASSIGN_OR_RETURN(auto x, expr)` : evaluates expr (a StatusOr), returns its
/// status on error, otherwise moves the value into `lhs`.
#define MRVS_ASSIGN_OR_RETURN(lhs, expr) \
  MRVS_ASSIGN_OR_RETURN_IMPL_(MRVS_STATUS_CONCAT_(mrvs_statusor_, __LINE__), lhs, expr)
#define MRVS_ASSIGN_OR_RETURN_IMPL_(tmp, lhs, expr) \
  auto tmp = (expr);                                \
  if (!tmp.ok()) return tmp.status();               \
  lhs = std::move(tmp).value()

// Note: Debian 12's absl is built with its own absl::string_view (not std::string_view).
// Build error messages with fmt::format into std::string and pass that to the absl
// status constructors; do not pass std::string_view to absl functions.
