// RGBN synthesis with synth/'s exemplar synthesiser (rgbn/synth.h, exemplar_*): colour and normal
// stay paired, normals stay unit, the saturation bound holds, a fill leaves everything outside
// the region alone and composes its detail on the base normals, and a seed fixes the result.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>

#include "core/error.h"
#include "rgbn/filter.h"
#include "rgbn/synth.h"
#include "support.h"

using namespace proctex::rgbn;
using rgbn_test::angle_deg;

namespace {

// A tileable field of random round stones: height = sum of toroidal Gaussian-ish domes, albedo a
// colour per stone (darker in the joints), plus a little per-pixel grain so that pixels differ.
Rgbn cobbles(int w, int h, unsigned seed, float depth = 6.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  HeightField z{w, h, std::vector<float>(size_t(w) * h, 0.0f)};
  std::vector<float> owner(size_t(w) * h, -1), best(size_t(w) * h, 0);
  std::vector<std::array<float, 3>> colours;
  const int stones = w * h / 150;
  for (int k = 0; k < stones; ++k) {
    const float cx = u(rng) * w, cy = u(rng) * h, r = 4 + 5 * u(rng);
    colours.push_back({0.25f + 0.5f * u(rng), 0.2f + 0.4f * u(rng), 0.15f + 0.3f * u(rng)});
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        float dx = std::fabs(x - cx), dy = std::fabs(y - cy);
        dx = std::min(dx, w - dx), dy = std::min(dy, h - dy);
        const float t = 1 - (dx * dx + dy * dy) / (r * r);
        if (t <= 0) continue;
        const size_t i = size_t(y) * w + x;
        const float v = depth * std::sqrt(t);
        if (v > best[i]) best[i] = v, owner[i] = float(k);
      }
  }
  for (size_t i = 0; i < z.z.size(); ++i) z.z[i] = best[i] + 0.3f * u(rng);
  Rgbn out = from_height(z, 1.0f, true);
  for (size_t i = 0; i < out.size(); ++i) {
    const float g = 0.9f + 0.1f * u(rng);
    for (int c = 0; c < 3; ++c)
      out.albedo[3 * i + c] = owner[i] < 0 ? 0.12f * g : colours[size_t(owner[i])][c] * g;
  }
  return out;
}

using Pair = std::array<float, 6>;
std::set<Pair> pairs_of(const Rgbn& im) {
  std::set<Pair> s;
  for (size_t i = 0; i < im.size(); ++i)
    s.insert({im.albedo[3 * i], im.albedo[3 * i + 1], im.albedo[3 * i + 2], im.normal[3 * i], im.normal[3 * i + 1],
              im.normal[3 * i + 2]});
  return s;
}
Pair pair_at(const Rgbn& im, size_t i) {
  return {im.albedo[3 * i], im.albedo[3 * i + 1], im.albedo[3 * i + 2], im.normal[3 * i], im.normal[3 * i + 1],
          im.normal[3 * i + 2]};
}

ExemplarSynthOptions options(uint64_t seed) {
  ExemplarSynthOptions o;
  o.seed = seed;
  return o;  // no cache: every test analyses afresh
}

}  // namespace

TEST(RgbnExemplarSynth, GrownPixelsAreExamplePairsUnitAndDeterministic) {
  const Rgbn ex = cobbles(64, 64, 5);
  const std::set<Pair> example = pairs_of(ex);
  ASSERT_GT(example.size(), ex.size() * 9 / 10);  // (almost) every example pair is distinct
  const ExemplarSynthResult r = exemplar_synthesize(ex, 150, 110, options(3));
  ASSERT_EQ(r.image.width, 150);
  ASSERT_EQ(r.image.height, 110);
  EXPECT_EQ(r.visited, size_t(150 * 110));
  std::set<Pair> used;
  for (size_t i = 0; i < r.image.size(); ++i) {
    const Pair p = pair_at(r.image, i);
    ASSERT_TRUE(example.count(p)) << "output pixel " << i << " is not an (albedo, normal) pair of the example";
    used.insert(p);
  }
  EXPECT_LT(max_norm_error(r.image), 1e-6);
  // Not a copy of one region: the output uses much of the example (a 150x110 output from a 64^2
  // example holds each example pixel ~4 times if spread evenly).
  EXPECT_GT(used.size(), ex.size() / 2);
  // Not the plain tiling either: neighbouring output pixels do not always continue the same offset.
  size_t breaks = 0;
  for (int y = 0; y < r.image.height; ++y)
    for (int x = 1; x < r.image.width; ++x) {
      const int a = r.source[size_t(y) * 150 + x - 1], b = r.source[size_t(y) * 150 + x];
      breaks += !(b % 64 == (a % 64 + 1) % 64 && b / 64 == a / 64);
    }
  EXPECT_GT(breaks, size_t(50));
  // The seed fixes the result; another seed changes it.
  const ExemplarSynthResult again = exemplar_synthesize(ex, 150, 110, options(3));
  EXPECT_EQ(again.image.albedo, r.image.albedo);
  EXPECT_EQ(again.image.normal, r.image.normal);
  const ExemplarSynthResult other = exemplar_synthesize(ex, 150, 110, options(4));
  EXPECT_NE(other.image.normal, r.image.normal);
}

TEST(RgbnExemplarSynth, SaturationBoundHoldsAfterGrowingAndFilling) {
  const Rgbn ex = cobbles(48, 48, 8, 14.0f);  // steep stones: many normals below 40 degrees
  size_t steep = 0;
  for (size_t i = 0; i < ex.size(); ++i) steep += ex.normal[3 * i + 2] < std::sin(40 * M_PI / 180);
  ASSERT_GT(steep, ex.size() / 20);
  ExemplarSynthOptions o = options(2);
  o.xi = 40;
  const ExemplarSynthResult g = exemplar_synthesize(ex, 80, 80, o);
  for (size_t i = 0; i < g.image.size(); ++i) ASSERT_GE(g.image.normal[3 * i + 2], std::sin(40 * M_PI / 180) - 1e-5);
  EXPECT_LT(max_norm_error(g.image), 1e-5);
  // Filling a tilted target with composed detail tilts it further; the bound still holds.
  Rgbn target(96, 72);
  const float t[3] = {0.5f, 0.2f, std::sqrt(1 - 0.29f)};
  for (size_t i = 0; i < target.size(); ++i) std::copy(t, t + 3, &target.normal[3 * i]);
  const Mask mask = disc_mask(96, 72, 50, 36, 22);
  o.compose = true;
  const ExemplarSynthResult f = exemplar_fill(ex, target, mask, o);
  for (size_t i = 0; i < f.image.size(); ++i)
    if (mask[i] > 0) ASSERT_GE(f.image.normal[3 * i + 2], std::sin(40 * M_PI / 180) - 1e-5) << i;
  EXPECT_LT(max_norm_error(f.image), 1e-5);
}

TEST(RgbnExemplarSynth, FillKeepsOutsideCopiesPairsAndComposesOnTheBase) {
  const Rgbn ex = cobbles(64, 64, 11);
  const std::set<Pair> example = pairs_of(ex);
  Rgbn target = cobbles(120, 90, 12, 3.0f);
  // A hole of two parts: a disc and a rectangle.
  Mask mask = disc_mask(120, 90, 40, 40, 20);
  const Mask rect = rect_mask(120, 90, 80, 50, 30, 25);
  for (size_t i = 0; i < mask.size(); ++i) mask[i] = std::max(mask[i], rect[i]);
  size_t inside = 0;
  for (float m : mask) inside += m > 0;

  // Without compose: inside, (albedo, normal) pairs of the example; outside, the target's bits.
  ExemplarSynthResult r = exemplar_fill(ex, target, mask, options(6));
  EXPECT_EQ(r.visited, inside);
  for (size_t i = 0; i < target.size(); ++i) {
    if (mask[i] > 0) {
      ASSERT_TRUE(example.count(pair_at(r.image, i))) << i;
    } else {
      ASSERT_EQ(pair_at(r.image, i), pair_at(target, i)) << "pixel " << i << " outside the region changed";
    }
  }
  // The chosen window matches the ring around the hole at least as well as any other tried:
  // more candidate windows can only lower the ring error.
  ExemplarSynthOptions one = options(6);
  one.windows = 1;
  EXPECT_LE(r.ring_error, exemplar_fill(ex, target, mask, one).ring_error);

  // With compose on a tilted, curved base: the albedo is still an example colour, the normal
  // makes the same angle with the target's base normal as the example normal with its own base
  // (detail composed in the local frame), and outside nothing changes.
  Rgbn tilted = from_height(rgbn_test::periodic_field(120, 90, 3, 6.0f), 1.0f, false);
  tilted.albedo = target.albedo;
  ExemplarSynthOptions co = options(6);
  co.compose = true;
  r = exemplar_fill(ex, tilted, mask, co);
  const Rgbn eb = base_normals(ex, co.base_sigma), tb = base_normals(tilted, co.base_sigma);
  double worst = 0, mean_tilt = 0;
  for (size_t i = 0; i < tilted.size(); ++i) {
    if (!(mask[i] > 0)) {
      ASSERT_EQ(pair_at(r.image, i), pair_at(tilted, i));
      continue;
    }
    const int s = r.source[i];
    ASSERT_GE(s, 0);
    ASSERT_TRUE(std::equal(&r.image.albedo[3 * i], &r.image.albedo[3 * i + 3], &ex.albedo[3 * size_t(s)]));
    const double a_out = angle_deg(&r.image.normal[3 * i], &tb.normal[3 * i]);
    const double a_ex = angle_deg(&ex.normal[3 * size_t(s)], &eb.normal[3 * size_t(s)]);
    worst = std::max(worst, std::fabs(a_out - a_ex));
    const float up[3] = {0, 0, 1};
    mean_tilt += angle_deg(&tb.normal[3 * i], up) / double(inside);
  }
  EXPECT_LT(worst, 0.01);
  EXPECT_GT(mean_tilt, 5.0);  // the base really is tilted, so composing is not the identity
  EXPECT_LT(max_norm_error(r.image), 1e-5);
  // Deterministic for a seed.
  const ExemplarSynthResult again = exemplar_fill(ex, tilted, mask, co);
  EXPECT_EQ(again.image.normal, r.image.normal);
  EXPECT_EQ(again.window_x, r.window_x);
}

TEST(RgbnExemplarSynth, ExamplesOutsideSynthLimitsAreUsageErrors) {
  EXPECT_THROW(exemplar_synthesize(Rgbn(8, 40), 64, 64, options(1)), proctex::UsageError);
  EXPECT_THROW(exemplar_synthesize(Rgbn(600, 40), 64, 64, options(1)), proctex::UsageError);
  ExemplarSynthOptions bad = options(1);
  bad.xi = 95;
  EXPECT_THROW(exemplar_synthesize(cobbles(32, 32, 1), 64, 64, bad), proctex::UsageError);
  const Rgbn target(40, 40);
  EXPECT_THROW(exemplar_fill(cobbles(32, 32, 1), target, Mask(10, 1.0f), options(1)), proctex::Error);
}

TEST(RgbnExemplarSynth, LargeFillsScoredOnRingTilesGiveTheSameResult) {
  // A 500^2 hole: its ring's 64^2 tiles cover under half the window, so candidates are scored on
  // them alone (synth/ is spatially deterministic); the result must equal whole-window scoring.
  const Rgbn ex = cobbles(64, 64, 21);
  Rgbn target = from_height(rgbn_test::periodic_field(560, 560, 22, 8.0f), 1.0f, false);
  const Mask mask = rect_mask(560, 560, 30, 30, 500, 500);
  ExemplarSynthOptions o = options(13);
  o.windows = 3;
  const ExemplarSynthResult tiles = exemplar_fill(ex, target, mask, o);
  o.tile_scoring = false;
  const ExemplarSynthResult whole = exemplar_fill(ex, target, mask, o);
  EXPECT_EQ(tiles.window_x, whole.window_x);
  EXPECT_EQ(tiles.window_y, whole.window_y);
  EXPECT_EQ(tiles.ring_error, whole.ring_error);
  EXPECT_EQ(tiles.image.normal, whole.image.normal);
  EXPECT_EQ(tiles.image.albedo, whole.image.albedo);
  EXPECT_EQ(tiles.visited, size_t(500 * 500));
}
