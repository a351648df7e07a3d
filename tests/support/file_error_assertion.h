#pragma once
// GoogleTest assertion for the project's file errors: the call must throw a FileError whose
// message is one line, starts with "<path>: " and contains `fragment`.
#include <gtest/gtest.h>

#include <string>

#include "protocol/files/file_error.h"

namespace skinstream::test {

template <typename Call>
::testing::AssertionResult throws_file_error(Call&& call, const std::string& path, const std::string& fragment) {
  try {
    call();
  } catch (const FileError& e) {
    const std::string message = e.what();
    if (message.find('\n') != std::string::npos) return ::testing::AssertionFailure() << "multi-line: " << message;
    if (message.rfind(path + ": ", 0) != 0) return ::testing::AssertionFailure() << "does not name the file: " << message;
    if (message.find(fragment) == std::string::npos)
      return ::testing::AssertionFailure() << "lacks '" << fragment << "': " << message;
    return ::testing::AssertionSuccess() << message;
  } catch (const std::exception& e) {
    return ::testing::AssertionFailure() << "threw a non-FileError: " << e.what();
  }
  return ::testing::AssertionFailure() << "did not throw";
}

}  // namespace skinstream::test
