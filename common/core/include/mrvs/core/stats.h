#pragma once
// Small order statistics for reports, benchmarks and tests.
#include <vector>

namespace mrvs {

/// The q-quantile (q in [0, 1]) of `values` by nearest rank: the element at index
/// round(q * (n - 1)) of the sorted values. NaN for an empty vector.
double quantile(std::vector<double> values, double q);

}  // namespace mrvs
