// The source's frame numbers: a jump counts the numbers skipped; going back, repeating or jumping
// by more than a minute of frames is a new numbering, not a loss; numbers wrap at 2^32.
#include "server/ingest/frame_numbering.h"

#include <gtest/gtest.h>

namespace skinstream::server {
namespace {

TEST(FrameNumbering, CountsTheNumbersAJumpSkipped) {
  FrameNumbering numbering;
  EXPECT_EQ(numbering.next(100, 120.0).skipped, 0u);  // the first continues nothing
  EXPECT_FALSE(numbering.next(101, 120.0).renumbered);
  const FrameNumbering::Step step = numbering.next(105, 120.0);
  EXPECT_EQ(step.skipped, 3u);
  EXPECT_FALSE(step.renumbered);
  EXPECT_EQ(numbering.next(106, 120.0).skipped, 0u);
}

TEST(FrameNumbering, GoingBackRepeatingOrAJumpBeyondAMinuteIsANewNumbering) {
  FrameNumbering numbering;
  numbering.next(5000, 120.0);
  for (uint32_t number : {10u, 10u, 10u + 120u * 60u + 1u}) {
    SCOPED_TRACE(number);
    const FrameNumbering::Step step = numbering.next(number, 120.0);
    EXPECT_TRUE(step.renumbered);
    EXPECT_EQ(step.skipped, 0u);
  }
  // A minute exactly is still counted; at 1 kHz a minute is 60,000 frames.
  EXPECT_EQ(numbering.next(10u + 120u * 60u + 1u + 120u * 60u, 120.0).skipped, 120u * 60u - 1u);
  numbering.next(0, 1000.0);
  EXPECT_EQ(numbering.next(50000, 1000.0).skipped, 49999u);
}

TEST(FrameNumbering, WrapsAt32BitsAsTheSourcesCountersDo) {
  FrameNumbering numbering;
  numbering.next(0xFFFFFFFEu, 120.0);
  EXPECT_EQ(numbering.next(1, 120.0).skipped, 2u);  // ...FF and 0 skipped
}

TEST(FrameNumbering, ARestartContinuesNothing) {
  FrameNumbering numbering;
  numbering.next(10, 120.0);
  numbering.restart();
  const FrameNumbering::Step step = numbering.next(500, 120.0);
  EXPECT_EQ(step.skipped, 0u);
  EXPECT_FALSE(step.renumbered);
}

}  // namespace
}  // namespace skinstream::server
