// The XML QTM answers GetParameters with, as skinstream's QTM client reads it
// (parse_parameters_xml, expat underneath): any text is read or refused with a one-line reason;
// what is read keeps the parser's limits (labels of at most 1 kB, at most 100,000 of them) and
// a finite, non-negative frequency.
#include <cmath>
#include <cstdlib>
#include <string>
#include <string_view>

#include "fuzz/one_line_file_error.h"
#include "protocol/qtm/qtm_parameters.h"

namespace qtm = skinstream::qtm;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  qtm::Parameters parameters;
  std::string error;
  if (!qtm::parse_parameters_xml(std::string_view(reinterpret_cast<const char*>(data), size), parameters, error)) {
    skinstream::fuzz::expect_one_printable_line(error);
    return 0;
  }
  if (!std::isfinite(parameters.frequency_hz) || parameters.frequency_hz < 0.0) std::abort();
  if (parameters.labels.size() > 100'000 || (!parameters.has_3d && !parameters.labels.empty())) std::abort();
  for (const std::string& label : parameters.labels)
    if (label.size() > 1024) std::abort();
  return 0;
}
