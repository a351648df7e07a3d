#pragma once
// Prints a run's report: the JSON as it is, or a few lines for a person.
#include <nlohmann/json.hpp>

namespace skinstream::bench {

void print_report(const nlohmann::json& report, bool as_json);

}  // namespace skinstream::bench
