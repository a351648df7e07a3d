#include "core/evaluation/error_stats.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace skinstream {

ErrorStats summarize_errors(std::vector<double> values) {
  ErrorStats stats;
  if (values.empty()) return stats;
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  stats.count = static_cast<int>(n);
  stats.mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(n);
  stats.median = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  // Integer arithmetic for the rank: 0.95 * n in floating point can land just above an integer.
  const size_t rank = std::max<size_t>(1, (95 * n + 99) / 100);
  stats.p95 = values[rank - 1];
  stats.max = values.back();
  return stats;
}

}  // namespace skinstream
