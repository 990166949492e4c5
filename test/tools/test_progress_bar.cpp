#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "progress_bar.h"

using evidential_octomap::tools::ProgressBar;

TEST(ProgressBar, FormatShowsBarCountPercentRateAndEta) {
  // 3 of 10 in 2 s: 1.50 scan/s, 7 left -> 4.67 s -> "0:05".
  EXPECT_EQ(ProgressBar::format("mapping", 3, 10, 2.0, "scan", 10),
            "mapping [###-------] 3/10  30%  1.50 scan/s  ETA 0:05");
}

TEST(ProgressBar, FormatBeforeAnythingIsDoneHasNoRate) {
  EXPECT_EQ(ProgressBar::format("", 0, 4, 0.0, "scan", 4), "[----] 0/4  0%  -- scan/s  ETA --:--");
}

TEST(ProgressBar, FormatWhenDoneIsFullAndClampsOvershoot) {
  EXPECT_EQ(ProgressBar::format("x", 12, 10, 5.0, "it", 5), "x [#####] 10/10  100%  2.00 it/s  ETA 0:00");
}

TEST(ProgressBar, DurationFormatting) {
  EXPECT_EQ(ProgressBar::formatDuration(5.4), "0:05");
  EXPECT_EQ(ProgressBar::formatDuration(754), "12:34");
  EXPECT_EQ(ProgressBar::formatDuration(3723), "1:02:03");
  EXPECT_EQ(ProgressBar::formatDuration(-1), "--:--");
  EXPECT_EQ(ProgressBar::formatDuration(1.0 / 0.0), "--:--");
}

TEST(ProgressBar, DisabledBarWritesNothing) {
  std::ostringstream out;
  {
    ProgressBar bar(3, "quiet", "scan", out, false);
    bar.tick();
    bar.tick(2);
    bar.finish();
  }
  EXPECT_TRUE(out.str().empty());
}

TEST(ProgressBar, EnabledBarRedrawsInPlaceAndEndsWithNewline) {
  std::ostringstream out;
  {
    ProgressBar bar(2, "load", "scan", out, true);
    bar.tick();
    bar.tick();
  }  // destructor finishes
  const std::string s = out.str();
  EXPECT_EQ(s.front(), '\r');
  EXPECT_NE(s.find("2/2  100%"), std::string::npos);
  EXPECT_EQ(s.back(), '\n');
  EXPECT_EQ(std::count(s.begin(), s.end(), '\n'), 1);
}

TEST(ProgressBar, AutoModeIsQuietWhenStderrIsNotATty) {
  // ctest runs us with stderr redirected; the auto mode must then be off.
  if (isatty(fileno(stderr))) GTEST_SKIP() << "stderr is a terminal here";
  ProgressBar bar(1, "auto");
  EXPECT_FALSE(bar.enabled());
}
