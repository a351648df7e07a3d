#pragma once
// Small helpers shared by the subcommands for JSON output.
#include <nlohmann/json.hpp>

#include "core/evaluation/error_stats.h"

namespace skinstream::cli {

inline nlohmann::json to_json(const ErrorStats& s) {
  return {{"count", s.count}, {"mean", s.mean}, {"median", s.median}, {"p95", s.p95}, {"max", s.max}};
}

}  // namespace skinstream::cli
