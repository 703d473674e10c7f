// Tests of the registered-pixel metric (metrics/aligned.h) that search/ uses for the last,
// continuous part of recovering a deterministic pattern: it ignores where the pattern starts and
// which colours it has, and sees what the statistical metrics barely see (a duty, a soft edge).
#include <gtest/gtest.h>

#include <cmath>

#include "metrics/aligned.h"

using namespace proctex;
using namespace proctex::metrics;

namespace {

struct Rgb {
  float r, g, b;
};

// Vertical bars: `count` periods across, a fraction `duty` of each in colour `a`, the rest `b`,
// with a linear edge ramp `soft` periods wide; shifted right by `shift` pixels.
Image bars(int size, int count, double duty, double soft, Rgb a, Rgb b, int shift = 0) {
  Image img(size, size);
  const double period = double(size) / count;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const double t = std::fmod((x - shift + 0.5 + 10 * size) / period, 1.0);  // phase in the period
      const double d = std::min(std::abs(t - duty / 2), 1.0);                   // distance from the bar's centre
      double m = d < duty / 2 ? 1.0 : 0.0;
      if (soft > 0) m = std::clamp((duty / 2 + soft / 2 - std::min(d, 1 - d)) / soft, 0.0, 1.0);
      float* p = img.pixel(x, y);
      p[0] = float(b.r + (a.r - b.r) * m);
      p[1] = float(b.g + (a.g - b.g) * m);
      p[2] = float(b.b + (a.b - b.b) * m);
    }
  return img;
}

double distance(const AlignedMetric& m, const Image& a, const Image& b) {
  return m.distance(m.features(a, 256).values, m.features(b, 256).values);
}

const Rgb kRed{0.6f, 0.1f, 0.05f}, kCream{0.8f, 0.75f, 0.6f}, kBlue{0.05f, 0.1f, 0.7f};

}  // namespace

TEST(Aligned, SamePatternShiftedAndRecolouredIsEqual) {
  const AlignedMetric m;
  const Image target = bars(256, 8, 0.3, 0.0, kRed, kCream);
  // 12 px to the right (6 px at the metric's 128 px), and in other (even swapped) colours.
  EXPECT_LT(distance(m, target, bars(256, 8, 0.3, 0.0, kBlue, kRed, 12)), 1e-3);
  EXPECT_LT(distance(m, target, bars(256, 8, 0.3, 0.0, kCream, kRed)), 1e-3);
}

TEST(Aligned, SeesDutyAndSoftnessThatShiftsAndColoursCannotExplain) {
  const AlignedMetric m;
  const Image target = bars(256, 8, 0.3, 0.0, kRed, kCream);
  const double wider = distance(m, target, bars(256, 8, 0.4, 0.0, kRed, kCream));
  const double softer = distance(m, target, bars(256, 8, 0.3, 0.15, kRed, kCream));
  const double near_duty = distance(m, target, bars(256, 8, 0.34, 0.0, kRed, kCream));
  EXPECT_GT(wider, 0.05);
  EXPECT_GT(softer, 0.01);
  // Monotone near the truth: what lets a local search walk to the exact duty.
  EXPECT_LT(near_duty, 0.5 * wider);
  EXPECT_GT(near_duty, 1e-3);
}

TEST(Aligned, IsSymmetricAndFlatImagesAreFarFromPatterns) {
  const AlignedMetric m;
  const Image a = bars(256, 8, 0.3, 0.0, kRed, kCream);
  const Image b = bars(256, 5, 0.5, 0.1, kBlue, kCream, 7);
  EXPECT_NEAR(distance(m, a, b), distance(m, b, a), 1e-6);
  const Image flat = bars(256, 8, 0.3, 0.0, kCream, kCream);
  EXPECT_GT(distance(m, a, flat), 0.03);  // nothing to align: the pattern's own energy
}

TEST(Aligned, BestShiftIsWhereThePatternStarts) {
  // Bars 10 px further right at 256 px are 5 px at the metric's 128: a(x + 5) = b(x) for a = the
  // shifted image (its bars start 5 px later), so best_shift(a, b) = (5, 0).
  const AlignedMetric m;
  const Image a = bars(256, 3, 0.3, 0.0, kRed, kCream, 10);
  const Image b = bars(256, 3, 0.3, 0.0, kBlue, kCream);
  const auto [dx, dy] = m.best_shift(m.features(a, 256).values, m.features(b, 256).values);
  EXPECT_EQ(dx, 5);
  EXPECT_EQ(dy, 0);
}

// register_rgb: how exactly a render reproduces a target in its own colours, where the pattern
// may start elsewhere. A match calls a deterministic result "pixel-exact" on it (search/match.h).
namespace {

// RGB RMS of render(x + dx, y + dy) against target(x, y) on the overlap: the definition, by hand.
double rmse_at(const Image& target, const Image& render, int dx, int dy) {
  const int n = target.width;
  double sum = 0;
  size_t count = 0;
  for (int y = std::max(0, -dy); y < std::min(n, n - dy); ++y)
    for (int x = std::max(0, -dx); x < std::min(n, n - dx); ++x, ++count)
      for (int c = 0; c < 3; ++c) sum += std::pow(double(render.pixel(x + dx, y + dy)[c]) - target.pixel(x, y)[c], 2);
  return std::sqrt(sum / (3.0 * count));
}

}  // namespace

TEST(Aligned, RegistrationFindsTheShiftThatReproducesThePixels) {
  const Image target = bars(256, 8, 0.3, 0.1, kRed, kCream);
  // The same bars starting 12 px further right: render(x + 12, y) = target(x, y).
  const auto r = AlignedMetric::register_rgb(target, bars(256, 8, 0.3, 0.1, kRed, kCream, 12));
  EXPECT_LT(r.rmse, 1e-4);
  EXPECT_EQ(r.dx, 12);
  EXPECT_EQ(r.dy, 0);
}

TEST(Aligned, RegistrationComparesColoursAsTheyAre) {
  const Image target = bars(256, 8, 0.5, 0.0, kRed, kCream);
  // Swapped colours at duty 0.5 are the same bars half a period (16 px) on: exact there only.
  const auto swapped = AlignedMetric::register_rgb(target, bars(256, 8, 0.5, 0.0, kCream, kRed));
  EXPECT_LT(swapped.rmse, 1e-4);
  EXPECT_EQ(std::abs(swapped.dx), 16);
  // Other colours are not explained away (the aligned metric's distance would call them equal).
  const auto recoloured = AlignedMetric::register_rgb(target, bars(256, 8, 0.5, 0.0, kBlue, kCream));
  EXPECT_GT(recoloured.rmse, 0.1);
  EXPECT_NEAR(recoloured.rmse, rmse_at(target, bars(256, 8, 0.5, 0.0, kBlue, kCream), recoloured.dx, recoloured.dy), 1e-4);
}

TEST(Aligned, RegistrationReportsTheBestShiftsResidual) {
  // A slightly wider duty: no shift explains it; the reported RMS is the hand-computed one at the
  // reported shift, and no other shift in a neighbourhood does better.
  const Image target = bars(256, 8, 0.3, 0.0, kRed, kCream);
  const Image render = bars(256, 8, 0.34, 0.0, kRed, kCream, 5);
  const auto r = AlignedMetric::register_rgb(target, render);
  EXPECT_NEAR(r.rmse, rmse_at(target, render, r.dx, r.dy), 1e-4);
  for (int dy = -3; dy <= 3; ++dy)
    for (int dx = r.dx - 3; dx <= r.dx + 3; ++dx) EXPECT_GE(rmse_at(target, render, dx, dy) + 1e-6, r.rmse);
  EXPECT_GT(r.rmse, 0.02);
}
