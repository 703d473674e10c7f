// synth/: the properties of parallel controllable synthesis a user relies on (digest
// notes/exemplar-synthesis.md, "Testable properties"), on the real OpenCL device (PoCL).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <filesystem>
#include <map>
#include <set>

#include "core/error.h"
#include "image/image.h"
#include "synth/analysis.h"
#include "synth/render.h"
#include "synth/synthesis.h"
#include "tests/support/temp_dir.h"

namespace proctex::synth {
namespace {

// A toroidal exemplar: every row and column continues across the wrap, and every 5x5 neighbourhood
// is unique (integer hash noise on a smooth periodic pattern).
Image periodic_exemplar(int m) {
  Image im(m, m);
  for (int y = 0; y < m; ++y)
    for (int x = 0; x < m; ++x) {
      uint32_t h = static_cast<uint32_t>(x * 73856093u) ^ static_cast<uint32_t>(y * 19349663u);
      h ^= h >> 13;
      h *= 0x5bd1e995u;
      h ^= h >> 15;
      const float noise = (h & 1023) / 1023.0f;
      const float wave = 0.5f + 0.25f * std::sin(2 * M_PI * 3 * x / m) * std::cos(2 * M_PI * 2 * y / m);
      float* p = im.pixel(x, y);
      p[0] = 0.7f * wave + 0.3f * noise;
      p[1] = 0.5f * wave + 0.2f * noise;
      p[2] = 0.3f + 0.4f * noise;
    }
  return im;
}

// A real photo (gravel, CC0, 512^2 grey), reduced to `size` (keeps it quick).
Image photo(int size) {
  static const Image full = load_image(std::filesystem::path(PROCTEX_SHARED_DIR) / "textures" / "gravel.png");
  return resize(crop(full, 0, 0, 256, 256), size, size);
}

Exemplar exemplar_of(Image im, const std::string& name = "test") {
  Exemplar ex;
  ex.name = name;
  ex.colour = std::move(im);
  return ex;
}

const Analysis& periodic_analysis() {
  static const Analysis a = [] {
    AnalysisOptions o;
    o.tiling = Tiling::Toroidal;
    return analyse(exemplar_of(periodic_exemplar(64)), o);
  }();
  return a;
}

const Analysis& photo_analysis() {
  static const Analysis a = analyse(exemplar_of(photo(64)));
  return a;
}

TEST(SynthAnalysis, LevelsSpacingAndCoherentCandidatesAreDispersed) {
  const Analysis& a = periodic_analysis();
  ASSERT_EQ(a.levels, 6);  // 64 = 2^6
  ASSERT_EQ(static_cast<int>(a.level.size()), 7);
  EXPECT_TRUE(a.toroidal);
  for (int l = 0; l <= a.levels; ++l) {
    EXPECT_EQ(a.level[l].spacing, 1 << (a.levels - l));
    // k = 2: the second candidate is at least 5% of the size (>= 3 px here) away, toroidally.
    for (int i = 0; i < 64 * 64; ++i) {
      const int c = a.level[l].coherent[i];
      int dx = std::abs(c % 64 - i % 64), dy = std::abs(c / 64 - i / 64);
      dx = std::min(dx, 64 - dx), dy = std::min(dy, 64 - dy);
      ASSERT_GE(std::max(dx, dy), 3) << "level " << l << " texel " << i;
    }
  }
  // At the finest level the second candidate should look alike: its neighbourhood distance is far
  // below the distance to a random texel on average.
  const auto& lv = a.level[a.levels];
  double near = 0, random = 0;
  for (int i = 0; i < 64 * 64; ++i) {
    const int c = lv.coherent[i], r = (i * 2654435761u) % (64 * 64);
    for (int k = 0; k < kAppearanceDims; ++k) {
      near += std::pow(lv.neighbourhood[i * 8 + k] - lv.neighbourhood[c * 8 + k], 2);
      random += std::pow(lv.neighbourhood[i * 8 + k] - lv.neighbourhood[r * 8 + k], 2);
    }
  }
  EXPECT_LT(near, 0.5 * random);
}

// A brick-like lattice of 128 x 128 px: periods 32 x 16 px (rows offset by half a brick every other
// row: the lattice is spanned by (32, 0) and (16, 16)), plus a little noise.
Image lattice_exemplar() {
  const int m = 128;
  Image im(m, m);
  for (int y = 0; y < m; ++y)
    for (int x = 0; x < m; ++x) {
      const int row = y / 16, bx = (x + (row % 2) * 16) % 32, by = y % 16;
      const bool mortar = bx < 3 || by < 3;
      uint32_t hsh = static_cast<uint32_t>(x * 2654435761u) ^ static_cast<uint32_t>(y * 40503u);
      hsh ^= hsh >> 15;
      const float noise = (hsh % 1000) / 1000.0f * 0.08f;
      float* p = im.pixel(x, y);
      p[0] = (mortar ? 0.1f : 0.5f + 0.1f * std::sin(bx * 0.4f) * std::cos(by * 0.5f)) + noise;
      p[1] = p[0] * 0.9f;
      p[2] = p[0] * 0.8f;
    }
  return im;
}

TEST(SynthAnalysis, SelfSimilarShiftsAreTheLatticeOfAPeriodicExemplar) {
  // The most self-similar shifts of a brick-like lattice must be lattice vectors, never near 0.
  const int m = 128;
  const Image im = lattice_exemplar();
  AnalysisOptions o;
  o.tiling = Tiling::Toroidal;
  const Analysis a = analyse(exemplar_of(im), o);
  ASSERT_GE(a.shifts.size(), 16u);
  for (size_t k = 0; k < 8; ++k) {
    const int dx = a.shifts[2 * k], dy = a.shifts[2 * k + 1];
    EXPECT_TRUE(8 * std::abs(dx) >= m || 8 * std::abs(dy) >= m) << k;
    // (dx, dy) = i (32, 0) + j (16, 16): dy a multiple of 16, dx - dy a multiple of 32.
    EXPECT_EQ(((dy % 16) + 16) % 16, 0) << "shift " << k << ": " << dx << "," << dy;
    EXPECT_EQ((((dx - dy) % 32) + 32) % 32, 0) << "shift " << k << ": " << dx << "," << dy;
  }
}

TEST(SynthAnalysis, SeamDetection) {
  EXPECT_TRUE(tiles_seamlessly(exemplar_of(periodic_exemplar(64))));
  // A ramp does not wrap: its last column is far from its first.
  Image ramp(32, 32);
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x)
      for (int c = 0; c < 3; ++c) ramp.pixel(x, y)[c] = (x + y) / 64.0f;
  EXPECT_FALSE(tiles_seamlessly(exemplar_of(ramp)));
  // A tiling brick pattern whose border runs along a mortar line (a sharp but natural step) tiles.
  Image bricks(64, 64);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const int row = y / 16, bx = (x + (row % 2) * 16) % 32;
      const bool mortar = y % 16 == 0 || bx == 0;
      const float n = ((x * 7 + y * 13) % 11) / 110.0f;
      for (int c = 0; c < 3; ++c) bricks.pixel(x, y)[c] = mortar ? 0.8f : 0.25f + n;
    }
  EXPECT_TRUE(tiles_seamlessly(exemplar_of(bricks)));
  // A crop of a photo does not.
  EXPECT_FALSE(tiles_seamlessly(exemplar_of(photo(64))));
}

TEST(SynthAnalysis, CacheRoundTripAndDamagedCacheIsIgnored) {
  testing::TempDir dir;
  const Exemplar ex = exemplar_of(photo(32));
  const Analysis first = analyse_cached(ex, {}, dir.path());
  EXPECT_FALSE(first.from_cache);
  const Analysis second = analyse_cached(ex, {}, dir.path());
  EXPECT_TRUE(second.from_cache);
  EXPECT_EQ(first.hash, second.hash);
  for (int l = 0; l <= first.levels; ++l) {
    EXPECT_EQ(first.level[l].appearance, second.level[l].appearance);
    EXPECT_EQ(first.level[l].neighbourhood, second.level[l].neighbourhood);
    EXPECT_EQ(first.level[l].coherent, second.level[l].coherent);
  }
  // Truncate the cache file: the next call analyses again (and rewrites it).
  const auto file = dir.path() / (first.hash + ".bin");
  ASSERT_TRUE(std::filesystem::exists(file));
  std::filesystem::resize_file(file, std::filesystem::file_size(file) / 2);
  const Analysis third = analyse_cached(ex, {}, dir.path());
  EXPECT_FALSE(third.from_cache);
  EXPECT_EQ(third.level.back().coherent, first.level.back().coherent);
  // Another exemplar gets another hash.
  Image other = photo(32);
  other.pixel(3, 3)[0] += 0.25f;
  EXPECT_NE(analyse_cached(exemplar_of(other), {}, dir.path()).hash, first.hash);
}

// k = 3 (--candidates 3): a third candidate per texel, dispersed from the texel and from the second
// one, and cached under its own key, so a k = 2 cache is never read as k = 3 (or the reverse).
TEST(SynthAnalysis, ThreeCandidatesAreDispersedAndCachedApart) {
  testing::TempDir dir;
  const Exemplar ex = exemplar_of(photo(40));
  AnalysisOptions o3;
  o3.candidates = 3;
  const Analysis two = analyse_cached(ex, {}, dir.path());
  const Analysis three = analyse_cached(ex, o3, dir.path());
  EXPECT_FALSE(three.from_cache);
  EXPECT_NE(two.hash, three.hash);
  EXPECT_EQ(three.candidates, 3);
  const int n = 40 * 40, sep = 2;  // 5% of 40 px, at least 2
  auto apart = [&](int a, int b) { return std::max(std::abs(a % 40 - b % 40), std::abs(a / 40 - b / 40)) >= sep; };
  for (int l = 0; l <= three.levels; ++l) {
    EXPECT_TRUE(two.level[l].coherent2.empty());
    ASSERT_EQ(static_cast<int>(three.level[l].coherent2.size()), n);
    for (int i = 0; i < n; ++i) {
      const int c1 = three.level[l].coherent[i], c2 = three.level[l].coherent2[i];
      ASSERT_TRUE(apart(i, c2) && apart(c1, c2)) << "level " << l << " texel " << i;
    }
  }
  const Analysis again = analyse_cached(ex, o3, dir.path());
  EXPECT_TRUE(again.from_cache);
  EXPECT_EQ(again.candidates, 3);
  EXPECT_EQ(again.level.back().coherent2, three.level.back().coherent2);
  EXPECT_TRUE(analyse_cached(ex, {}, dir.path()).level.back().coherent2.empty());
  AnalysisOptions o4;
  o4.candidates = 4;
  EXPECT_THROW(analyse(ex, o4), UsageError);
}

TEST(Synth, ZeroRandomnessOnAToroidalExemplarIsTheExactTiling) {
  Synthesizer s(periodic_analysis());
  SynthOptions o;
  o.randomness = {0.0f};
  const Window w{-37, 1000003, 150, 130};
  const auto S = s.synthesise(w, o);
  // S[p] = (p + c) mod 64 for one constant c.
  const int cx = static_cast<int>(((S[0] - w.x) % 64 + 64) % 64);
  const int cy = static_cast<int>(((S[1] - w.y) % 64 + 64) % 64);
  for (int y = 0; y < w.height; ++y)
    for (int x = 0; x < w.width; ++x) {
      const size_t i = static_cast<size_t>(y) * w.width + x;
      ASSERT_EQ(S[2 * i], ((w.x + x + cx) % 64 + 64) % 64) << x << "," << y;
      ASSERT_EQ(S[2 * i + 1], ((w.y + y + cy) % 64 + 64) % 64) << x << "," << y;
    }
}

TEST(Synth, SameSeedSameMapOtherSeedOtherMap) {
  Synthesizer s(photo_analysis());
  SynthOptions o;
  const Window w{0, 0, 96, 96};
  const auto a = s.synthesise(w, o);
  const auto b = s.synthesise(w, o);
  EXPECT_EQ(a, b);
  o.seed = 2;
  const auto c = s.synthesise(w, o);
  size_t differ = 0;
  for (size_t i = 0; i < a.size(); i += 2) differ += a[i] != c[i] || a[i + 1] != c[i + 1];
  EXPECT_GT(differ, a.size() / 2 / 2) << "another seed should change most of the map";
}

// Copies the window `part` out of a synthesis of `whole` (both on the same plane).
std::vector<int32_t> cut(const std::vector<int32_t>& S, const Window& whole, const Window& part) {
  std::vector<int32_t> out;
  for (int y = 0; y < part.height; ++y)
    for (int x = 0; x < part.width; ++x) {
      const size_t i = static_cast<size_t>(part.y - whole.y + y) * whole.width + (part.x - whole.x + x);
      out.push_back(S[2 * i]);
      out.push_back(S[2 * i + 1]);
    }
  return out;
}

TEST(Synth, AnyWindowEqualsTheSameRegionOfALargerSynthesis) {
  Synthesizer s(photo_analysis());
  SynthOptions o;
  o.seed = 77;
  o.randomness = {1.0f, 0.8f, 0.6f, 0.4f, 0.3f};
  for (const int64_t ox : {int64_t(0), int64_t(-123457), int64_t(1) << 40, -(int64_t(1) << 50) + 3}) {
    const Window whole{ox, -ox / 3 - 5, 256, 192};
    const auto big = s.synthesise(whole, o);
    // 16 windows of 64 x 48 tile the big one exactly.
    for (int ty = 0; ty < 4; ++ty)
      for (int tx = 0; tx < 4; ++tx) {
        const Window part{whole.x + 64 * tx, whole.y + 48 * ty, 64, 48};
        ASSERT_EQ(s.synthesise(part, o), cut(big, whole, part)) << "offset " << ox << " tile " << tx << "," << ty;
      }
    // Odd offsets and sizes, a single pixel, a single row.
    for (const Window part : {Window{whole.x + 17, whole.y + 33, 101, 57}, Window{whole.x + 255, whole.y + 191, 1, 1},
                              Window{whole.x + 3, whole.y + 100, 250, 1}}) {
      ASSERT_EQ(s.synthesise(part, o), cut(big, whole, part)) << "offset " << ox;
    }
  }
}

TEST(Synth, PerLevelPassesKeepWindowsExact) {
  // A different number of correction passes per level changes each level's reach (padding): any
  // window must still equal the same region of a larger synthesis.
  Synthesizer s(photo_analysis());
  SynthOptions o;
  o.seed = 9;
  o.randomness = {1.0f, 0.5f, 0.0f};
  o.passes = {3, 0, 1, 2};
  o.finest_passes = 2;
  const Window whole{-(int64_t(1) << 33) + 7, 12345, 160, 96};
  const auto big = s.synthesise(whole, o);
  for (const Window part : {Window{whole.x, whole.y, 40, 96}, Window{whole.x + 41, whole.y + 13, 77, 50},
                            Window{whole.x + 159, whole.y + 95, 1, 1}})
    ASSERT_EQ(s.synthesise(part, o), cut(big, whole, part));
  // The passes matter: without them the map is another one.
  SynthOptions none = o;
  none.passes = {0};
  none.finest_passes = 0;
  EXPECT_NE(s.synthesise(whole, none), big);
  // Bad values are refused.
  o.passes = {9};
  EXPECT_THROW(s.synthesise({0, 0, 8, 8}, o), UsageError);
  o.passes = {2};
  o.finest_passes = -2;
  EXPECT_THROW(s.synthesise({0, 0, 8, 8}, o), UsageError);
}

// Fraction of horizontally adjacent pixel pairs whose coordinates continue the exemplar (a
// verbatim-copied patch); `column` < 0 means every column, else only pairs (column, column + 1).
double coherence(const std::vector<int32_t>& S, int w, int h, int ew, int column = -1) {
  long coherent = 0, total = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x + 1 < w; ++x) {
      if (column >= 0 && x != column) continue;
      const size_t i = static_cast<size_t>(y) * w + x;
      coherent += S[2 * i + 2] == (S[2 * i] + 1) % ew && S[2 * i + 3] == S[2 * i + 1];
      ++total;
    }
  return double(coherent) / total;
}

TEST(Synth, SeamRefinementKeepsWindowsExactAndPatchesWhole) {
  // The refinement's 2 checkerboard sub-passes read 2 pixels around: a window must still equal the same region
  // of a larger synthesis (also a single pixel), on a toroidal and on a bounded exemplar.
  for (const bool torus : {true, false}) {
    Synthesizer s(torus ? periodic_analysis() : photo_analysis());
    SynthOptions o;
    o.seed = 4;
    o.refine_passes = 2;
    const Window whole{(int64_t(1) << 41) - 3, -999, 144, 112};
    const auto big = s.synthesise(whole, o);
    for (const Window part : {Window{whole.x + 5, whole.y, 60, 112}, Window{whole.x + 71, whole.y + 37, 73, 41},
                              Window{whole.x + 100, whole.y + 50, 1, 1}})
      ASSERT_EQ(s.synthesise(part, o), cut(big, whole, part)) << torus;
    // It moves joins between patches (the map changes) and takes only positions that continue a
    // neighbour's patch, so the patches do not break up: the share of adjacent pixels continuing
    // a patch does not fall.
    SynthOptions plain = o;
    plain.refine_passes = 0;
    const auto before = s.synthesise(whole, plain);
    EXPECT_NE(before, big) << torus;
    const int ew = s.analysis().width;
    EXPECT_GE(coherence(big, whole.width, whole.height, ew), coherence(before, whole.width, whole.height, ew) - 0.005)
        << torus;
  }
  SynthOptions bad;
  bad.refine_passes = 9;
  Synthesizer s(periodic_analysis());
  EXPECT_THROW(s.synthesise({0, 0, 8, 8}, bad), UsageError);
}

// The bench's coherence measure, brute force: RMS (0-255 sRGB codes) over output 7x7 RGB patches on
// a 4 px grid of the distance to the nearest 7x7 patch of the exemplar.
double patch_coherence(const Image& out, const Image& ex) {
  auto code = [](const Image& im, int x, int y, int c) {
    return 255.0f * linear_to_srgb(std::clamp(im.pixel(x, y)[c], 0.0f, 1.0f));
  };
  std::vector<float> e;  // exemplar patches, 147 values each
  for (int y = 3; y + 3 < ex.height; ++y)
    for (int x = 3; x + 3 < ex.width; ++x)
      for (int dy = -3; dy <= 3; ++dy)
        for (int dx = -3; dx <= 3; ++dx)
          for (int c = 0; c < 3; ++c) e.push_back(code(ex, x + dx, y + dy, c));
  const size_t n = e.size() / 147;
  double total = 0;
  long count = 0;
  float q[147];
  for (int y = 3; y + 3 < out.height; y += 4)
    for (int x = 3; x + 3 < out.width; x += 4) {
      int k = 0;
      for (int dy = -3; dy <= 3; ++dy)
        for (int dx = -3; dx <= 3; ++dx)
          for (int c = 0; c < 3; ++c) q[k++] = code(out, x + dx, y + dy, c);
      float best = 1e30f;
      for (size_t i = 0; i < n; ++i) {
        float d = 0;
        const float* r = &e[i * 147];
        for (int t = 0; t < 147 && d < best; ++t) d += (q[t] - r[t]) * (q[t] - r[t]);
        best = std::min(best, d);
      }
      total += best;
      ++count;
    }
  return std::sqrt(total / count / 147);
}

TEST(Synth, FinalRematchKeepsWindowsExactAndPatchesWhole) {
  // The re-match's 2 checkerboard sub-passes read 3 pixels around: windows stay exact (toroidal and bounded
  // exemplars, a single pixel) and the thread count does not matter (covered by the determinism test).
  for (const bool torus : {true, false}) {
    Synthesizer s(torus ? periodic_analysis() : photo_analysis());
    SynthOptions o;
    o.seed = 6;
    o.rematch_passes = 2;
    const Window whole{-(int64_t(1) << 37) + 11, 4321, 136, 104};
    const auto big = s.synthesise(whole, o);
    for (const Window part : {Window{whole.x + 3, whole.y, 61, 104}, Window{whole.x + 64, whole.y + 29, 72, 45},
                              Window{whole.x + 135, whole.y + 7, 1, 1}})
      ASSERT_EQ(s.synthesise(part, o), cut(big, whole, part)) << torus;
    SynthOptions plain = o;
    plain.rematch_passes = 0;
    EXPECT_NE(s.synthesise(whole, plain), big) << torus;
  }
  // The bench's coherence measure on the photo, over 4 seeds, and patches stay whole.
  Synthesizer s(photo_analysis());
  const Image ex = photo(64);
  const Window w{0, 0, 128, 128};
  double with = 0, without = 0;
  for (const uint32_t seed : {1u, 2u, 3u, 4u}) {
    SynthOptions o;
    o.seed = seed;
    o.rematch_passes = 0;
    const auto before = s.synthesise(w, o);
    o.rematch_passes = SynthOptions{}.rematch_passes;
    const auto after = s.synthesise(w, o);
    const double b = patch_coherence(colours_of(before, w.width, w.height, ex), ex);
    const double a = patch_coherence(colours_of(after, w.width, w.height, ex), ex);
    without += b;
    with += a;
    // It may take a k-coherence candidate (a new join) where that fits better, but patches stay
    // whole: the share of adjacent pixels continuing a patch (~0.95 before) falls by at most 0.045
    // with the default 2 passes (0.028-0.036 seen; 0.02 with one pass after a seam refinement).
    EXPECT_GE(coherence(after, w.width, w.height, 64), coherence(before, w.width, w.height, 64) - 0.045) << seed;
  }
  // On this small, noisy photo the re-match moves the measure by less than 1% either way (on the
  // bench's 128 px exemplars it lowered it; docs/synth.md): it must at least not damage the output.
  EXPECT_LT(with, 1.01 * without) << "with " << with / 4 << " without " << without / 4;
  SynthOptions bad;
  bad.rematch_passes = 9;
  EXPECT_THROW(s.synthesise({0, 0, 8, 8}, bad), UsageError);
  bad = SynthOptions{};
  bad.rematch_candidate_passes = -1;
  EXPECT_THROW(s.synthesise({0, 0, 8, 8}, bad), UsageError);
}

TEST(Synth, ThreeCandidatesKeepWindowsExactAndChangeOnlyTheRematch) {
  // --candidates 3: the third candidate enters the re-match (3 px read radius, as before), so windows
  // stay exact on toroidal and bounded exemplars; without the re-match the map is k = 2's.
  AnalysisOptions o3;
  o3.candidates = 3;
  for (const bool torus : {true, false}) {
    const Analysis a3 = torus ? analyse(exemplar_of(periodic_exemplar(64)), [&] {
      AnalysisOptions o = o3;
      o.tiling = Tiling::Toroidal;
      return o;
    }())
                              : analyse(exemplar_of(photo(64)), o3);
    Synthesizer s3(a3), s2(torus ? periodic_analysis() : photo_analysis());
    SynthOptions o;
    o.seed = 9;
    const Window whole{-(int64_t(1) << 35) + 5, -77, 120, 96};
    const auto big = s3.synthesise(whole, o);
    for (const Window part : {Window{whole.x + 1, whole.y, 59, 96}, Window{whole.x + 60, whole.y + 31, 60, 40},
                              Window{whole.x + 119, whole.y + 95, 1, 1}})
      ASSERT_EQ(s3.synthesise(part, o), cut(big, whole, part)) << torus;
    SynthOptions plain = o;
    plain.rematch_passes = 0;
    EXPECT_EQ(s3.synthesise(whole, plain), s2.synthesise(whole, plain)) << torus;
  }
}

TEST(Synth, LayoutShiftsKeepTheRowsOfALatticeAligned) {
  // With structure-keeping layout shifts every first-level block is moved by a lattice vector of
  // the brick-like exemplar, so the output's rows continue across blocks: (S_y - y) mod 16 (the row
  // phase) is the same almost everywhere. With uniform shifts the blocks' row phases differ.
  AnalysisOptions ao;
  ao.tiling = Tiling::Toroidal;
  const Analysis a = analyse(exemplar_of(lattice_exemplar()), ao);
  Synthesizer s(a);
  const Window w{-1000, 333, 256, 256};
  auto row_phase_share = [&](int shifts) {
    SynthOptions o;
    o.layout_shifts = shifts;
    const auto S = s.synthesise(w, o);
    std::map<int, long> phases;
    for (int y = 0; y < w.height; ++y)
      for (int x = 0; x < w.width; ++x) {
        const size_t i = static_cast<size_t>(y) * w.width + x;
        ++phases[static_cast<int>(((S[2 * i + 1] - (w.y + y)) % 16 + 16) % 16)];
      }
    long most = 0;
    for (const auto& [phase, count] : phases) most = std::max(most, count);
    return double(most) / (w.width * w.height);
  };
  const double structured = row_phase_share(16), uniform = row_phase_share(0);
  EXPECT_GT(structured, 0.9) << "uniform " << uniform;
  EXPECT_LT(uniform, 0.6) << "structured " << structured;
  // Still randomised (not a tiling): another seed, another map; windows stay exact.
  SynthOptions o;
  o.layout_shifts = 16;
  const auto big = s.synthesise(w, o);
  const Window part{w.x + 37, w.y + 101, 90, 77};
  EXPECT_EQ(s.synthesise(part, o), cut(big, w, part));
  o.seed = 2;
  EXPECT_NE(s.synthesise(w, o), big);
  o.layout_shifts = kMaxShifts + 1;
  EXPECT_THROW(s.synthesise({0, 0, 8, 8}, o), UsageError);
}

TEST(Synth, LayoutShiftsOnlyForAnExemplarThatResemblesItselfUnderThem) {
  // The lattice's shifts are lattice vectors: the exemplar correlates strongly with itself under
  // them, so the default threshold keeps all of them.
  AnalysisOptions ao;
  ao.tiling = Tiling::Toroidal;
  const Analysis a = analyse(exemplar_of(lattice_exemplar()), ao);
  ASSERT_EQ(a.shift_correlation.size(), a.shifts.size() / 2);
  EXPECT_GT(a.shift_correlation[0], 0.5f);
  SynthOptions o;
  o.layout_shifts = 16;
  EXPECT_EQ(layout_shift_count(a, o), 16);
  o.layout_min_correlation = 0.99f;  // nothing is that self-similar on average: uniform shifts
  EXPECT_EQ(layout_shift_count(a, o), 0);
  // Shifts whose "peaks" are anti-correlated (dirt's, all near half the exemplar) are not used.
  Analysis anti = a;
  for (auto& c : anti.shift_correlation) c = -0.2f;
  EXPECT_EQ(layout_shift_count(anti, SynthOptions{}), 0);
  SynthOptions always;
  always.layout_min_correlation = -1.0f;
  EXPECT_EQ(layout_shift_count(anti, always), std::min<int>(always.layout_shifts, static_cast<int>(a.shifts.size() / 2)));
  o.layout_min_correlation = 1.5f;
  Synthesizer s(a);
  EXPECT_THROW(s.synthesise({0, 0, 8, 8}, o), UsageError);
}

TEST(Synth, BreakingPiecesChangesTheMapKeepsWindowsExactAndRowsAligned) {
  AnalysisOptions ao;
  ao.tiling = Tiling::Toroidal;
  const Analysis a = analyse(exemplar_of(lattice_exemplar()), ao);
  Synthesizer s(a);
  const Window w{-5000, 777, 256, 192};
  SynthOptions o;
  o.layout_shifts = 16;
  const auto plain = s.synthesise(w, o);
  o.break_pieces = 0.5f;
  const auto broken = s.synthesise(w, o);
  EXPECT_NE(broken, plain);
  for (const Window part : {Window{w.x + 3, w.y + 50, 61, 99}, Window{w.x + 200, w.y, 56, 1}})
    EXPECT_EQ(s.synthesise(part, o), cut(broken, w, part)) << part.x << "," << part.y;
  // The further shifts are lattice vectors too: the rows stay aligned.
  std::map<int, long> phases;
  for (int y = 0; y < w.height; ++y)
    for (int x = 0; x < w.width; ++x) {
      const size_t i = static_cast<size_t>(y) * w.width + x;
      ++phases[static_cast<int>(((broken[2 * i + 1] - (w.y + y)) % 16 + 16) % 16)];
    }
  long most = 0;
  for (const auto& [phase, count] : phases) most = std::max(most, count);
  EXPECT_GT(double(most) / (w.width * w.height), 0.9);
  o.break_pieces = 1.5f;
  EXPECT_THROW(s.synthesise({0, 0, 8, 8}, o), UsageError);
}

// Pieces copied verbatim: regions of 4-connected pixels copying the exemplar with one offset (S - p
// modulo the m x m exemplar). Returns the largest piece and the area-weighted mean piece (the size
// of the piece a random pixel lies in), both in pixels.
std::pair<long, double> copied_pieces(const std::vector<int32_t>& S, int w, int h, int m) {
  std::vector<int> offset(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      offset[i] = ((S[2 * i] - x) % m + m) % m + m * (((S[2 * i + 1] - y) % m + m) % m);
    }
  std::vector<char> seen(offset.size(), 0);
  long largest = 0;
  double weighted = 0;
  for (size_t s0 = 0; s0 < offset.size(); ++s0) {
    if (seen[s0]) continue;
    std::vector<size_t> stack{s0};
    seen[s0] = 1;
    long n = 0;
    while (!stack.empty()) {
      const size_t c = stack.back();
      stack.pop_back();
      ++n;
      const int x = static_cast<int>(c % w), y = static_cast<int>(c / w);
      const int nb[4][2] = {{x - 1, y}, {x + 1, y}, {x, y - 1}, {x, y + 1}};
      for (const auto& q : nb) {
        if (q[0] < 0 || q[1] < 0 || q[0] >= w || q[1] >= h) continue;
        const size_t k = static_cast<size_t>(q[1]) * w + q[0];
        if (!seen[k] && offset[k] == offset[c]) seen[k] = 1, stack.push_back(k);
      }
    }
    largest = std::max(largest, n);
    weighted += double(n) * n;
  }
  return {largest, weighted / offset.size()};
}

TEST(Synth, CopiedPiecesStaySmallerThanTheExemplar) {
  // The output must be a new arrangement, not regions of the exemplar tiled. On a brick-like
  // lattice (whose layout shifts continue each other) a pixel of a 512^2 output lies, on average
  // over 4 seeds, in a verbatim piece of at most 0.35 of the exemplar, and the largest piece is
  // smaller than the exemplar on average (0.25 and 0.85 in session 10). With a correction at the
  // second level (issue 13's sessions 3-9) the blocks merged: 0.49 and 1.52 here, 3.5 exemplars in
  // one piece on the bench's brick photo.
  AnalysisOptions ao;
  ao.tiling = Tiling::Toroidal;
  const Analysis a = analyse(exemplar_of(lattice_exemplar()), ao);
  Synthesizer s(a);
  const double area = double(a.width) * a.height;
  double largest = 0, mean = 0;
  for (uint32_t seed : {1u, 2u, 3u, 4u}) {
    SynthOptions o;
    o.seed = seed;
    const Window w{-777, 4096, 512, 512};
    const auto [big, weighted] = copied_pieces(s.synthesise(w, o), w.width, w.height, a.width);
    largest += big / area / 4;
    mean += weighted / area / 4;
  }
  EXPECT_LT(mean, 0.35) << "a pixel's verbatim piece, in exemplars";
  EXPECT_LT(largest, 1.0) << "the largest verbatim piece, in exemplars";
}

TEST(Synth, OutputIsNeitherATilingNorNoise) {
  Synthesizer s(photo_analysis());
  const Window w{0, 0, 192, 192};
  const auto S = s.synthesise(w, {});
  const double c = coherence(S, w.width, w.height, 64);
  EXPECT_LT(c, 0.97) << "default randomness must break the tiling";
  EXPECT_GT(c, 0.35) << "synthesis should copy coherent patches, not scatter single texels";
  // Patches come from all over the exemplar: every 8x8 block of the exemplar is used.
  std::set<int> blocks;
  for (size_t i = 0; i < S.size(); i += 2) blocks.insert(S[i] / 8 + 8 * (S[i + 1] / 8));
  EXPECT_GE(blocks.size(), 56u);
}

TEST(Synth, TileableOutputWrapsWithoutASeam) {
  Synthesizer s(photo_analysis());
  SynthOptions o;
  o.period_x = 128;
  o.period_y = 128;
  o.seed = 5;
  // The plane is periodic: the window [0, 256) is four copies of [0, 128).
  const auto S = s.synthesise({0, 0, 256, 256}, o);
  const auto tile = s.synthesise({0, 0, 128, 128}, o);
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x) {
      const size_t i = static_cast<size_t>(y) * 256 + x, j = static_cast<size_t>(y % 128) * 128 + x % 128;
      ASSERT_EQ(S[2 * i], tile[2 * j]);
      ASSERT_EQ(S[2 * i + 1], tile[2 * j + 1]);
    }
  // No seam: pairs across the wrap (column 127 -> 128) continue patches about as often as inner pairs.
  const double inner = coherence(S, 256, 256, 64);
  const double seam = coherence(S, 256, 256, 64, 127);
  EXPECT_GT(seam, 0.6 * inner) << "inner " << inner << " seam " << seam;
  // And a period that is not a multiple of 2 is refused.
  o.period_x = o.period_y = 127;
  EXPECT_THROW(s.synthesise({0, 0, 8, 8}, o), UsageError);
}

TEST(Synth, SmallTileablePeriodIsStillRandomised) {
  // A period of 16 px on a 64 px exemplar (6 levels) leaves only levels 3..6 to synthesise: the
  // randomness list starts at the first of them, so the default (jitter the first level) still
  // breaks the tiling instead of skipping its only non-zero value.
  Synthesizer s(photo_analysis());
  SynthOptions o;
  o.period_x = o.period_y = 16;
  ASSERT_EQ(first_level(photo_analysis(), o), 3);
  const auto S = s.synthesise({0, 0, 64, 64}, o);
  // Randomised: another seed gives another map (without jitter the seed would change nothing).
  SynthOptions other = o;
  other.seed = 2;
  EXPECT_NE(s.synthesise({0, 0, 64, 64}, other), S) << "a tileable output must not be the plain tiling";
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const size_t i = static_cast<size_t>(y) * 64 + x, j = static_cast<size_t>(y % 16) * 64 + x % 16;
      ASSERT_EQ(S[2 * i], S[2 * j]);
      ASSERT_EQ(S[2 * i + 1], S[2 * j + 1]);
    }
}

TEST(Synth, BoundedExemplarIsNotCopiedAcrossItsBorder) {
  // A photo crop does not tile; patches must not run from its right edge into its left edge.
  const Analysis& a = photo_analysis();
  ASSERT_FALSE(a.toroidal);
  Synthesizer s(a);
  const Window w{0, 0, 256, 256};
  const auto S = s.synthesise(w, {});
  long across = 0, pairs = 0;
  for (int y = 0; y < w.height; ++y)
    for (int x = 0; x + 1 < w.width; ++x) {
      const size_t i = static_cast<size_t>(y) * w.width + x;
      across += S[2 * i] == 63 && S[2 * i + 2] == 0 && S[2 * i + 3] == S[2 * i + 1];
      ++pairs;
    }
  // Inside the exemplar a column boundary is continued ~coherence * pairs / 64 times; across the
  // border it must be much rarer.
  const double per_column = coherence(S, w.width, w.height, 64) * pairs / 64.0;
  EXPECT_LT(across, 0.25 * per_column) << across << " vs " << per_column;
}

TEST(Synth, ApplyMapsStayAligned) {
  // A map that is a function of the colour stays that function of the output colour.
  Exemplar ex = exemplar_of(photo(64));
  ExemplarMap m;
  m.name = "inverse";
  m.kind = MapKind::Grey;
  m.image = Image(64, 64);
  for (size_t i = 0; i < m.image.pixels.size(); ++i) m.image.pixels[i] = 1.0f - ex.colour.pixels[i];
  ex.maps.push_back(m);
  const Analysis a = analyse(ex);
  Synthesizer s(a);
  const Window w{5, 9, 100, 80};
  testing::TempDir dir;
  RenderOutputs out;
  out.colour = dir / "c.exr";
  out.maps = {dir / "m.exr"};
  out.coords = dir / "uv.exr";
  render(s, ex, w, {}, out, {}, 100 * 17);  // strips of 17 rows
  const Image c = load_image(out.colour), mm = load_image(out.maps[0]), uv = load_image(out.coords);
  ASSERT_EQ(c.width, 100);
  ASSERT_EQ(mm.height, 80);
  const auto S = s.synthesise(w, {});
  for (size_t i = 0; i < static_cast<size_t>(100 * 80); ++i) {
    ASSERT_NEAR(c.pixels[3 * i] + mm.pixels[3 * i], 1.0f, 2e-3f) << i;
    ASSERT_EQ(uv.pixels[3 * i], S[2 * i]);
    ASSERT_EQ(uv.pixels[3 * i + 1], S[2 * i + 1]);
  }
}

}  // namespace
}  // namespace proctex::synth

namespace proctex::synth {
namespace {

TEST(Synth, JitterMapScalesTheRandomnessWhereItIsPainted) {
  Synthesizer s(photo_analysis());
  const Window w{-40, 30, 128, 96};
  SynthOptions o;
  o.randomness = {1.0f, 1.0f, 0.6f, 0.3f};
  const auto plain = s.synthesise(w, o);
  SynthOptions white = o, black = o, none = o;
  white.jitter_map.assign(8 * 8, 255);
  white.jitter_map_width = white.jitter_map_height = 8;
  black.jitter_map.assign(8 * 8, 0);
  black.jitter_map_width = black.jitter_map_height = 8;
  none.randomness = {0.0f};
  EXPECT_EQ(s.synthesise(w, white), plain);       // white = the randomness as given
  EXPECT_EQ(s.synthesise(w, black), s.synthesise(w, none));  // black = no jitter at all
  // Half painted: the map still gives the same pixels for any window (it tiles the plane).
  SynthOptions half = o;
  half.jitter_map_width = half.jitter_map_height = 64;
  half.jitter_map.resize(64 * 64);
  for (int i = 0; i < 64 * 64; ++i) half.jitter_map[i] = (i % 64) < 32 ? 0 : 255;
  const auto whole = s.synthesise(w, half);
  const Window part{w.x + 37, w.y + 11, 50, 40};
  std::vector<int32_t> cut_out;
  for (int y = 0; y < part.height; ++y)
    for (int x = 0; x < part.width; ++x) {
      const size_t i = static_cast<size_t>(part.y - w.y + y) * w.width + (part.x - w.x + x);
      cut_out.push_back(whole[2 * i]);
      cut_out.push_back(whole[2 * i + 1]);
    }
  EXPECT_EQ(s.synthesise(part, half), cut_out);
  EXPECT_NE(whole, plain);
  SynthOptions bad = o;
  bad.jitter_map.assign(10, 1);
  bad.jitter_map_width = 4;
  bad.jitter_map_height = 4;
  EXPECT_THROW(s.synthesise(w, bad), UsageError);
}

}  // namespace
}  // namespace proctex::synth

namespace proctex::synth {
namespace {

TEST(Synth, PastedFeatureIsCopiedVerbatimAtItsPosition) {
  Synthesizer s(photo_analysis());
  SynthOptions o;
  o.seed = 4;
  o.pastes.push_back({10, 12, 30, 24, 1000, -500});  // exemplar (10,12) 30x24 -> plane (1000,-500)
  const Window w{960, -540, 128, 100};
  const auto S = s.synthesise(w, o);
  int exact = 0, inner = 0;
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 30; ++x) {
      const size_t i = static_cast<size_t>(-500 - w.y + y) * w.width + (1000 - w.x + x);
      const bool is_exact = S[2 * i] == 10 + x && S[2 * i + 1] == 12 + y;
      exact += is_exact;
      if (x >= 4 && x < 26 && y >= 4 && y < 20) {  // the border band is blended by correction
        ++inner;
        EXPECT_TRUE(is_exact) << x << "," << y << " -> " << S[2 * i] << "," << S[2 * i + 1];
      }
    }
  EXPECT_GT(inner, 0);
  EXPECT_GE(exact, 30 * 24 * 8 / 10) << "most of the rectangle, border included, is verbatim";
  // Without the paste that region is something else; a window of the pasted plane is exact too.
  SynthOptions plain = o;
  plain.pastes.clear();
  EXPECT_NE(s.synthesise(w, plain), S);
  const Window part{990, -510, 40, 30};
  std::vector<int32_t> cut_out;
  for (int y = 0; y < part.height; ++y)
    for (int x = 0; x < part.width; ++x) {
      const size_t i = static_cast<size_t>(part.y - w.y + y) * w.width + (part.x - w.x + x);
      cut_out.push_back(S[2 * i]);
      cut_out.push_back(S[2 * i + 1]);
    }
  EXPECT_EQ(s.synthesise(part, o), cut_out);
  SynthOptions bad = o;
  bad.pastes = {{50, 50, 30, 30, 0, 0}};  // leaves the 64 px exemplar
  EXPECT_THROW(s.synthesise(w, bad), UsageError);
}

}  // namespace
}  // namespace proctex::synth
