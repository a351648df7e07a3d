#pragma once
// Every file reader and writer reports a problem as a FileError whose message is one line
// naming the file and what is wrong, e.g. "walk.c3d: truncated: header says 900 frames, file holds 412".
#include <stdexcept>
#include <string>

namespace skinstream {

class FileError : public std::runtime_error {
 public:
  FileError(const std::string& path, const std::string& what) : std::runtime_error(path + ": " + what) {}
};

}  // namespace skinstream
