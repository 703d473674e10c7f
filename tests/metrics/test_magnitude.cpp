// Tests of the exact-pattern magnitude metric (metrics/magnitude.h) that search/ uses to polish a
// deterministic match: it tells stripe counts apart, ignores where the pattern starts, and its
// blurred form ranks a near miss above a far one.
#include <gtest/gtest.h>

#include <cmath>

#include "metrics/magnitude.h"

using namespace proctex;
using namespace proctex::metrics;

namespace {

// Vertical sine stripes: `count` periods across a size x size image, shifted by `phase` periods.
Image stripes(int size, double count, double phase = 0.0) {
  Image img(size, size);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const float v = float(0.5 + 0.4 * std::sin(2 * M_PI * (count * (x + 0.5) / size + phase)));
      for (int c = 0; c < 3; ++c) img.pixel(x, y)[c] = v;
    }
  return img;
}

// RMS magnitude difference (what the polish's similarity is a monotone function of).
double distance(const MagnitudeMetric& m, const Image& a, const Image& b, int resolution) {
  return m.distance(m.features(a, resolution).values, m.features(b, resolution).values);
}

}  // namespace

TEST(Magnitude, SameStripesShiftedAreEqualOtherCountsAreNot) {
  const MagnitudeMetric m(128);
  const Image target = stripes(256, 20);
  const double shifted = distance(m, target, stripes(256, 20, 0.37), 128);  // phase ignored
  const double one_more = distance(m, target, stripes(256, 21), 128);      // another pattern
  EXPECT_LT(shifted, 0.05 * one_more);
}

TEST(Magnitude, BlurRanksANearMissAboveAFarOne) {
  // Exact magnitudes score 2 and 9 stripes off alike (no overlapping peaks); blurred ones prefer
  // the near miss - what lets the polish's search walk towards the right count.
  const MagnitudeMetric exact(128), blurred(128, 2.0);
  const Image target = stripes(256, 30);
  const double exact_near = distance(exact, target, stripes(256, 32), 128);
  const double exact_far = distance(exact, target, stripes(256, 39), 128);
  EXPECT_NEAR(exact_near / exact_far, 1.0, 0.1);
  const double blurred_near = distance(blurred, target, stripes(256, 32), 128);
  const double blurred_far = distance(blurred, target, stripes(256, 39), 128);
  EXPECT_LT(blurred_near, 0.8 * blurred_far);
  // and the exact pattern is still the closest
  EXPECT_LT(distance(blurred, target, stripes(256, 30, 0.2), 128), 0.1 * blurred_near);
}
