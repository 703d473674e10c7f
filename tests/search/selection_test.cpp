// The shader selection's colour statistics (search/selection.h): CIELAB values a colour scientist
// would look up for the sRGB primaries and greys, in the documented order.
#include <gtest/gtest.h>

#include <cmath>

#include "search/selection.h"

namespace proctex::search {
namespace {

Image filled(int w, int h, float r, float g, float b) {
  Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      img.pixel(x, y)[0] = r;
      img.pixel(x, y)[1] = g;
      img.pixel(x, y)[2] = b;
    }
  return img;
}

// Order: mean/std of L*, a*, b*, C* (0-7), 10/50/90 % quantiles of L*, a*, b*, C* (8-19), hue cos/sin (20, 21).
TEST(Selection, ColourStatisticsOfAGreyAreNeutral) {
  // 18 % grey (linear): L* = 116 * 0.18^(1/3) - 16 = 49.5, no chroma.
  const auto s = colour_statistics(filled(64, 64, 0.18f, 0.18f, 0.18f));
  ASSERT_EQ(s.size(), kColourStatistics);
  EXPECT_NEAR(s[0], 49.5, 0.1);
  EXPECT_NEAR(s[1], 0.0, 1e-3);
  EXPECT_NEAR(s[2], 0.0, 0.05);
  EXPECT_NEAR(s[4], 0.0, 0.05);
  EXPECT_NEAR(s[6], 0.0, 0.05);
  EXPECT_NEAR(s[9], 49.5, 0.1);  // median L*
}

TEST(Selection, ColourStatisticsOfTheSrgbGreenPrimary) {
  // sRGB green (0, 1, 0): CIELAB (D65) L* 87.7, a* -86.2, b* 83.2, C* 119.8, hue 136 degrees.
  const auto s = colour_statistics(filled(32, 32, 0.0f, 1.0f, 0.0f));
  EXPECT_NEAR(s[0], 87.7, 0.2);
  EXPECT_NEAR(s[2], -86.2, 0.3);
  EXPECT_NEAR(s[4], 83.2, 0.3);
  EXPECT_NEAR(s[6], 119.8, 0.4);
  EXPECT_NEAR(std::atan2(s[21], s[20]) * 180.0 / M_PI, 136.0, 0.5);
}

TEST(Selection, ColourStatisticsSpreadAndQuantilesOfTwoColours) {
  // Left half black (L* 0), right half white (L* 100): mean 50, deviation 50, 10 % quantile 0,
  // 90 % quantile 100. The statistics come from the centre square, so a wide image gives the same.
  Image img = filled(64, 64, 0, 0, 0);
  for (int y = 0; y < 64; ++y)
    for (int x = 32; x < 64; ++x)
      for (int c = 0; c < 3; ++c) img.pixel(x, y)[c] = 1.0f;
  const auto s = colour_statistics(img);
  EXPECT_NEAR(s[0], 50.0, 0.1);
  EXPECT_NEAR(s[1], 50.0, 0.1);
  EXPECT_NEAR(s[8], 0.0, 0.1);
  EXPECT_NEAR(s[10], 100.0, 0.1);
  Image wide = filled(128, 64, 1, 0, 0);  // red margins outside the centre square
  for (int y = 0; y < 64; ++y)
    for (int x = 32; x < 96; ++x)
      for (int c = 0; c < 3; ++c) wide.pixel(x, y)[c] = img.pixel(x - 32, y)[c];
  const auto w = colour_statistics(wide);
  for (size_t i = 0; i < kColourStatistics; ++i) EXPECT_NEAR(w[i], s[i], 1e-6) << i;
}

}  // namespace
}  // namespace proctex::search
