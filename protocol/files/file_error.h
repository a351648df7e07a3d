#pragma once
// Every file reader and writer reports a problem as a FileError whose message is one line
// naming the file and what is wrong, e.g. "walk.c3d: truncated: header says 900 frames, file holds 412".
// The message is made printable (protocol/printable_text.h): whatever a file held that entered
// it (a label with a line break or a terminal escape, a megabyte-long name) cannot break the line.
#include <stdexcept>
#include <string>

#include "protocol/printable_text.h"

namespace skinstream {

class FileError : public std::runtime_error {
 public:
  FileError(const std::string& path, const std::string& what)
      : std::runtime_error(printable_text(path + ": " + what, kMaxMessageBytes)) {}
  static constexpr size_t kMaxMessageBytes = 1024;
};

}  // namespace skinstream
