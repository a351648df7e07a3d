#pragma once
// skinstream eval-deform: section 5 against the synthetic ground truth, every method side by
// side (rigid, quadratic, rigid + RBF, the full method, and sparse-marker linear blend skinning).
//   skinstream eval-deform [--motions breathe,flex,...] [--seconds 5] [--seed 1] [--subdivided]
//                          [--stride 4] [--render DIR] [--part-file P.json] [--part-file-out P.json] [--json]
#include <cstdint>
#include <cstdio>
#include <string>

#include "clients/skinstream/deform_evaluation.h"

namespace skinstream::cli {

struct EvalDeformOptions {
  std::string motions = "breathe,flex,golf,punch,jumprope";  // comma-separated
  double seconds = 5.0;          // each evaluated take
  double train_seconds = 20.0;   // the range-of-motion training take
  uint64_t seed = 1;             // of the takes (the same body and marker layout)
  bool subdivided = false;       // the once-subdivided body (~53,500 vertices)
  std::string body_dir;          // the MakeHuman files; empty: default_body_dir()
  std::string parts_out;         // also write the segmentation used
  DeformEvaluationOptions evaluation;
  bool json = false;             // JSON only, without the Markdown table
};

// Prints the JSON (and the table) to `out`, progress to stderr; returns the exit code.
int run_eval_deform(const EvalDeformOptions& options, std::FILE* out);

}  // namespace skinstream::cli
