#include "server/http/static_files.h"

#include <gtest/gtest.h>

#include <fstream>

#include "support/test_data.h"

namespace skinstream::server {
namespace {

namespace fs = std::filesystem;

class StaticFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ = test::scratch_path("static_files");
    fs::remove_all(base_);
    root_ = base_ / "web";
    fs::create_directories(root_ / "js");
    std::ofstream(root_ / "index.html") << "<html></html>";
    std::ofstream(root_ / "js" / "app.js") << "let x;";
    std::ofstream(base_ / "secret.txt") << "secret";
    fs::create_symlink(base_ / "secret.txt", root_ / "escape.txt");
  }
  fs::path base_, root_;
};

TEST_F(StaticFiles, ServesFilesInsideTheRoot) {
  EXPECT_EQ(resolve_static_file(root_, "/"), fs::canonical(root_ / "index.html"));
  EXPECT_EQ(resolve_static_file(root_, "/index.html?v=2"), fs::canonical(root_ / "index.html"));
  EXPECT_EQ(resolve_static_file(root_, "/js/app.js"), fs::canonical(root_ / "js" / "app.js"));
  EXPECT_EQ(resolve_static_file(root_, "/js/%61pp.js"), fs::canonical(root_ / "js" / "app.js"));
}

TEST_F(StaticFiles, RefusesEverythingThatLeavesTheRoot) {
  for (const char* target : {"/../secret.txt", "/js/../../secret.txt", "/%2e%2e/secret.txt", "/..%2fsecret.txt",
                             "/js/..\\..\\secret.txt", "/escape.txt", "/%00index.html", "/%zz", "relative.html",
                             "/missing.html", "/js"})
    EXPECT_FALSE(resolve_static_file(root_, target)) << target;
  EXPECT_FALSE(resolve_static_file("", "/index.html"));
}

TEST(ContentTypes, NamesTheWebTypes) {
  EXPECT_EQ(content_type_for("a/index.html"), "text/html; charset=utf-8");
  EXPECT_EQ(content_type_for("app.JS"), "text/javascript; charset=utf-8");
  EXPECT_EQ(content_type_for("s.css"), "text/css; charset=utf-8");
  EXPECT_EQ(content_type_for("i.png"), "image/png");
  EXPECT_EQ(content_type_for("d.json"), "application/json");
  EXPECT_EQ(content_type_for("m.wasm"), "application/wasm");
  EXPECT_EQ(content_type_for("blob"), "application/octet-stream");
}

}  // namespace
}  // namespace skinstream::server
