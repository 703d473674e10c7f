// The shader selection's colour statistics (search/selection.h): CIELAB values a colour scientist
// would look up for the sRGB primaries and greys, in the documented order.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

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


// Shape statistics (search::shape_statistics): per level, [0] coherence at 1.5 px, [1] its
// coherent share, [2] four-times-angle concentration, [3] coherence at 4 px, [4] its coherent
// share, [5] whole-level anisotropy, [6] ridge share, [7] blob share, [8] polarity.
constexpr size_t kPer = kShapeStatisticsPerLevel;

Image from_lightness(int side, const std::function<float(float, float)>& f) {
  Image img(side, side);
  for (int y = 0; y < side; ++y)
    for (int x = 0; x < side; ++x) {
      const float v = std::clamp(f(static_cast<float>(x), static_cast<float>(y)), 0.0f, 1.0f);
      for (int c = 0; c < 3; ++c) img.pixel(x, y)[c] = v;
    }
  return img;
}

Image stripes(float angle_degrees, float period = 12.0f) {
  const float a = angle_degrees * 3.14159265f / 180.0f;
  return from_lightness(256, [&](float x, float y) {
    return 0.5f + 0.4f * std::sin(6.2831853f * (x * std::cos(a) + y * std::sin(a)) / period);
  });
}

// White noise blurred a little: no preferred direction, no elongation.
Image isotropic_noise(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> n(0.0f, 1.0f);
  std::vector<float> v(256 * 256);
  for (float& x : v) x = n(rng);
  std::vector<float> b(v.size());
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x) {
      float s = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) s += v[((y + dy + 256) % 256) * 256 + (x + dx + 256) % 256];
      b[y * 256 + x] = s / 9.0f;
    }
  return from_lightness(256, [&](float x, float y) { return 0.5f + 0.3f * b[static_cast<int>(y) * 256 + static_cast<int>(x)]; });
}

TEST(Selection, ShapeStatisticsTellStripesFromNoise) {
  const auto s = shape_statistics(stripes(30.0f));
  const auto n = shape_statistics(isotropic_noise(3));
  ASSERT_EQ(s.size(), kShapeStatistics);
  // at the finest level: stripes are coherent at both integration scales, in one direction
  EXPECT_GT(s[0], 0.9);
  EXPECT_GT(s[3], 0.9);
  EXPECT_GT(s[5], 0.9);
  EXPECT_GT(s[6], 0.8);  // ridges, not blobs
  EXPECT_LT(n[0], 0.6);
  EXPECT_LT(n[3], 0.4);  // noise loses its coherence over a wide window
  EXPECT_LT(n[5], 0.1);
  EXPECT_GT(n[7], 0.2);  // blobs and pits
}

TEST(Selection, ShapeStatisticsDoNotDependOnRotationOrContrast) {
  const auto a = shape_statistics(stripes(10.0f));
  const auto b = shape_statistics(stripes(100.0f));
  const Image low_contrast = from_lightness(256, [](float x, float y) {
    return 0.5f + 0.1f * std::sin(6.2831853f * (x * std::cos(0.1745f) + y * std::sin(0.1745f)) / 12.0f);
  });
  const auto c = shape_statistics(low_contrast);
  for (size_t i = 0; i < kShapeStatistics; ++i) {
    if (i % kPer == 8) continue;  // polarity of a sinusoid is 0 +- discretisation noise
    EXPECT_NEAR(a[i], b[i], 0.05) << "statistic " << i;
    EXPECT_NEAR(a[i], c[i], 0.05) << "statistic " << i;
  }
}

TEST(Selection, ShapeStatisticsSeeTwoPerpendicularDirectionsOfAGrid) {
  // a grid of thin dark lines both ways: four-times-angle concentration high, one-direction low
  const Image grid = from_lightness(256, [](float x, float y) {
    return (static_cast<int>(x) % 16 < 2 || static_cast<int>(y) % 16 < 2) ? 0.1f : 0.8f;
  });
  const auto g = shape_statistics(grid);
  EXPECT_GT(g[2], 0.7);
  EXPECT_LT(g[5], 0.1);
  EXPECT_GT(g[8], 0.2);  // dark lines on a bright ground: valleys (positive curvature across them)
}


// Micro statistics (search::micro_statistics): per level, the square roots of the shares of the
// rotation-invariant uniform LBP labels, 10 for 8 neighbours at radius 1 (label k: k neighbours
// not darker than the centre, 9: not uniform) then 18 for 16 at radius 2.
constexpr size_t kMicroPer = kMicroStatisticsPerLevel;

TEST(Selection, MicroStatisticsLabelAFlatAreaAndIsolatedSpots) {
  const auto flat = micro_statistics(from_lightness(256, [](float, float) { return 0.4f; }));
  ASSERT_EQ(flat.size(), kMicroStatistics);
  for (int l = 0; l < kMicroLevels; ++l) {
    EXPECT_NEAR(flat[l * kMicroPer + 8], 1.0, 1e-9) << "level " << l;        // all neighbours equal
    EXPECT_NEAR(flat[l * kMicroPer + 10 + 16], 1.0, 1e-9) << "level " << l;  // the same at radius 2
  }
  // single bright pixels 8 px apart on a dark ground: each is a spot (label 0) at the finest level
  const auto spots = micro_statistics(from_lightness(256, [](float x, float y) {
    return static_cast<int>(x) % 8 == 4 && static_cast<int>(y) % 8 == 4 ? 0.9f : 0.1f;
  }));
  EXPECT_NEAR(spots[0] * spots[0], 1.0 / 64.0, 0.002);
}

TEST(Selection, MicroStatisticsDoNotDependOnRotationOrContrast) {
  const Image noise = isotropic_noise(5);
  Image turned = noise;  // a quarter turn
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x)
      for (int c = 0; c < 3; ++c) turned.pixel(x, y)[c] = noise.pixel(y, 255 - x)[c];
  Image faint = noise;  // half the contrast, brighter
  for (float& v : faint.pixels) v = 0.5f * v + 0.3f;
  const auto a = micro_statistics(noise), b = micro_statistics(turned), c = micro_statistics(faint);
  for (size_t i = 0; i < kMicroStatistics; ++i) {
    EXPECT_NEAR(a[i], b[i], 0.01) << "statistic " << i;
    EXPECT_NEAR(a[i], c[i], 0.03) << "statistic " << i;
  }
}

TEST(Selection, MicroStatisticsTellEdgesFromNoise) {
  // smooth stripes: every neighbourhood is a uniform pattern (an edge or a flat slope)
  const auto s = micro_statistics(stripes(30.0f, 24.0f));
  const auto n = micro_statistics(isotropic_noise(3));
  const double stripes_other = s[9] * s[9], noise_other = n[9] * n[9];
  EXPECT_LT(stripes_other, 0.05) << stripes_other;
  EXPECT_GT(noise_other, 0.1);  // 0.15 for this noise
  EXPECT_GT(noise_other, 3 * stripes_other);
}

}  // namespace
}  // namespace proctex::search
