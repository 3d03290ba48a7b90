#include "mrvs/core/stats.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mrvs {

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double rank = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const auto k = static_cast<std::ptrdiff_t>(std::floor(rank + 0.5));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[static_cast<std::size_t>(k)];
}

}  // namespace mrvs
