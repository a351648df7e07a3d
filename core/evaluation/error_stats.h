#pragma once
// Summary statistics of a set of non-negative errors (distances).

#include <vector>

namespace skinstream {

struct ErrorStats {
  int count = 0;
  double mean = 0.0;
  double median = 0.0;  // middle of the sorted values; mean of the two middle ones when count is even
  double p95 = 0.0;     // nearest rank: the ceil(0.95 * count)-th smallest value (1-based)
  double max = 0.0;
};

// All fields are 0 when `values` is empty (count tells the case apart).
ErrorStats summarize_errors(std::vector<double> values);

}  // namespace skinstream
