#pragma once
// skinstream eval-fill: delete seeded random gaps from a capture with no gaps, fill them with
// every method side by side, and report the error against the deleted samples.
#include <cstdio>
#include <string>

#include "core/evaluation/gap_plan.h"

namespace skinstream::cli {

struct EvalFillOptions {
  std::string capture_path;  // capture with no gaps (truth)
  std::string train_path;    // training capture of the same subject; empty: the first part of the capture
  double split = 0.5;        // without a training capture: train on this fraction, test on the rest
  std::string gap_protocol = "short";  // short: `gaps` as given; long: long_gap_plan(gaps.seed)
  GapPlanOptions gaps;
  int lookahead = 6;  // of the 'skinstream lookahead' row
  bool ablations = false;
  bool json = false;
};

// Prints the table (or its JSON) to `out`; returns the exit code. Throws on bad files, a test
// part with gaps, or a test capture without one of the subject's markers.
int run_eval_fill(const EvalFillOptions& options, std::FILE* out);

}  // namespace skinstream::cli
