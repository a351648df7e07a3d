#include "server/control/control_token.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "support/file_error_assertion.h"
#include "support/test_data.h"

namespace skinstream::server {
namespace {

const std::string kToken = "stage-token-0123456789";

std::string token_file(const std::string& name, const std::string& text, mode_t mode) {
  const std::string path = test::scratch_path(name);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
  EXPECT_EQ(::chmod(path.c_str(), mode), 0);
  return path;
}

std::string config_error_of(const std::string& file, const char* variable) {
  try {
    load_control_token(file, variable);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(ControlToken, NeitherFileNorVariableMeansTheControlApiIsOff) {
  EXPECT_EQ(load_control_token("", nullptr), std::nullopt);
  EXPECT_EQ(load_control_token("", ""), std::nullopt);
}

TEST(ControlToken, TheFilesFirstLineIsTheToken) {
  const std::string path = token_file("control-token-ok", kToken + " \r\nsecond line\n", 0600);
  EXPECT_EQ(load_control_token(path, nullptr), kToken);
  DaemonConfig config;
  config.control_token_file = path;
  ::unsetenv(kControlTokenVariable);
  EXPECT_EQ(load_control_token(config), kToken);
}

TEST(ControlToken, AFileEveryUserMayReadIsRefused) {
  const std::string path = token_file("control-token-world", kToken + "\n", 0644);
  EXPECT_TRUE(test::throws_file_error([&] { load_control_token(path, nullptr); }, path, "chmod 600"));
  ASSERT_EQ(::chmod(path.c_str(), 0640), 0);
  EXPECT_EQ(load_control_token(path, nullptr), kToken);
}

TEST(ControlToken, BadFilesAreOneLineErrorsWithoutTheToken) {
  const std::string missing = test::scratch_path("control-token-missing");
  EXPECT_TRUE(test::throws_file_error([&] { load_control_token(missing, nullptr); }, missing, "cannot read"));
  const std::string short_token = token_file("control-token-short", "short\n", 0600);
  EXPECT_TRUE(
      test::throws_file_error([&] { load_control_token(short_token, nullptr); }, short_token, "16-256"));
  const std::string spaced = token_file("control-token-spaced", "stage token 0123456789\n", 0600);
  try {
    load_control_token(spaced, nullptr);
    ADD_FAILURE() << "a token with spaces was taken";
  } catch (const FileError& e) {
    EXPECT_EQ(std::string(e.what()).find("stage token"), std::string::npos) << e.what();
  }
  const std::string empty = token_file("control-token-empty", "", 0600);
  EXPECT_TRUE(test::throws_file_error([&] { load_control_token(empty, nullptr); }, empty, "empty"));
  const std::string folder = test::scratch_path("control-token-folder");
  ::mkdir(folder.c_str(), 0700);
  EXPECT_TRUE(
      test::throws_file_error([&] { load_control_token(folder, nullptr); }, folder, "not a regular file"));
}

TEST(ControlToken, TheVariableIsTheAlternativeNotASecondToken) {
  EXPECT_EQ(load_control_token("", kToken.c_str()), kToken);
  EXPECT_NE(config_error_of("", "short").find(kControlTokenVariable), std::string::npos);
  const std::string path = token_file("control-token-both", kToken + "\n", 0600);
  EXPECT_NE(config_error_of(path, kToken.c_str()).find("given twice"), std::string::npos);
  EXPECT_EQ(config_error_of(path, kToken.c_str()).find(kToken), std::string::npos);
}

TEST(ControlToken, TheConfigurationHoldsThePathNotTheToken) {
  DaemonConfig config;
  config.control_token_file = token_file("control-token-printed", kToken + "\n", 0600);
  EXPECT_EQ(printable(config).dump().find(kToken), std::string::npos);
  EXPECT_EQ(printable(config).at("control_token_file"), config.control_token_file);
}

}  // namespace
}  // namespace skinstream::server
