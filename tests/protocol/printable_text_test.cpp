// Text from files and peers in one-line messages: escaped, cut, and so in every FileError.
#include "protocol/printable_text.h"

#include <gtest/gtest.h>

#include <string>

#include "protocol/files/file_error.h"

namespace skinstream {
namespace {

TEST(PrintableText, EscapesEveryByteOutsidePrintableAscii) {
  EXPECT_EQ(printable_text("LASI"), "LASI");
  EXPECT_EQ(printable_text(std::string("a\nb\rc\td\x1b[2Je\x7f", 13)), "a\\x0ab\\x0dc\\x09d\\x1b[2Je\\x7f");
  EXPECT_EQ(printable_text(std::string("nul\0x", 5)), "nul\\x00x");
  EXPECT_EQ(printable_text("M\xc3\xbcller\xff"), "M\\xc3\\xbcller\\xff");  // UTF-8 and invalid UTF-8 alike
  EXPECT_EQ(printable_text(""), "");
}

TEST(PrintableText, CutsLongTextSayingHowLongItWas) {
  const std::string long_name(1'000'000, 'x');
  EXPECT_EQ(printable_text(long_name, 8), "xxxxxxxx... (1000000 bytes)");
  EXPECT_EQ(printable_text("12345678", 8), "12345678");
  EXPECT_EQ(quoted_text(std::string(41, 'y')), "'" + std::string(40, 'y') + "... (41 bytes)'");
  EXPECT_EQ(quoted_text("a\nb"), "'a\\x0ab'");
}

TEST(FileError, MessageIsOnePrintableBoundedLineWhateverTheFileHeld) {
  const FileError e("take.trc", "marker name " + std::string("\x1b]0;owned\x07\n", 11) + std::string(100'000, 'z'));
  const std::string message = e.what();
  EXPECT_EQ(message.rfind("take.trc: marker name \\x1b]0;owned\\x07\\x0a", 0), 0u) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos);
  for (const char c : message) EXPECT_TRUE(c >= 0x20 && c < 0x7f) << static_cast<int>(c);
  EXPECT_LT(message.size(), FileError::kMaxMessageBytes + 32);
  EXPECT_NE(message.find("bytes)"), std::string::npos);
}

}  // namespace
}  // namespace skinstream
