// Tests of the pixel metric (metrics/pixels.h): the plain RGB difference at a fixed registration
// that the last step of recovering a deterministic pattern minimises (search/pixel_polish.h).
#include <gtest/gtest.h>

#include <cmath>

#include "metrics/aligned.h"
#include "core/error.h"
#include "metrics/pixels.h"

using namespace proctex;
using namespace proctex::metrics;

namespace {

// A diagonal ramp in three different channels, moved right by `shift` pixels (content enters
// from the left): distinct everywhere, so every shift but the true one leaves a difference.
Image ramp(int size, int shift = 0) {
  Image img(size, size);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const double u = x - shift;
      float* p = img.pixel(x, y);
      p[0] = float(0.5 + 0.4 * std::sin(u * 0.11 + y * 0.05));
      p[1] = float(0.5 + 0.4 * std::cos(u * 0.07 - y * 0.13));
      p[2] = float(0.3 + 0.2 * std::sin(u * 0.03 * y / size + 1.0));
    }
  return img;
}

}  // namespace

TEST(Pixels, DistanceIsTheMeanSquaredRgbDifference) {
  const PixelMetric m(64);
  Image a = ramp(64), b = ramp(64);
  // One pixel 0.3 brighter in red: 0.09 / (64 * 64 * 3) by hand.
  b.pixel(10, 20)[0] += 0.3f;
  const double expected = 0.09 / (64.0 * 64.0 * 3.0);
  EXPECT_NEAR(m.distance(m.features(a, 64).values, m.features(b, 64).values), expected, 1e-9);
  EXPECT_NEAR(m.rms(m.similarity(m.features(a, 64), m.features(b, 64))), std::sqrt(expected), 1e-6);
  EXPECT_EQ(m.similarity(m.features(a, 64), m.features(a, 64)), 1.0);
}

TEST(Pixels, TargetFeaturesFollowTheRegistrationConvention) {
  // register_rgb says render(x + dx, y + dy) ~ target(x, y); features of the target made for that
  // shift compare equal with the render on the overlap and are undefined (left out) elsewhere.
  const PixelMetric m(128);
  const Image target = ramp(128);
  const Image render = ramp(128, 9);  // the same content 9 px further right
  const auto reg = AlignedMetric::register_rgb(target, render);
  ASSERT_EQ(reg.dx, 9);
  ASSERT_EQ(reg.dy, 0);
  const auto rendered = m.features(render, 128);
  EXPECT_LT(m.distance(m.target_features(target, reg.dx, reg.dy).values, rendered.values), 1e-10);
  // Unregistered, the same render is far: the metric does not search shifts itself.
  EXPECT_GT(m.distance(m.target_features(target, 0, 0).values, rendered.values), 1e-3);
  // The left-out pixels are the 9 columns the moved target does not cover.
  const auto f = m.target_features(target, 9, 0);
  size_t undefined = 0;
  for (float v : f.values) undefined += std::isnan(v) ? 1 : 0;
  EXPECT_EQ(undefined, size_t(3 * 9 * 128));
}

TEST(Pixels, WrongSizedTargetIsAClearError) {
  const PixelMetric m(128);
  EXPECT_THROW(m.target_features(ramp(64), 0, 0), Error);
}
