// proctex match on the project's photos (issue 12): the matched shader is the material a person
// sees. The photos (../shared/textures, CC0) are in the tune half of the labelled set that the
// shader selection was fitted on (bench/realset, search/selection_model.h): these tests guard the
// product's answer on them; the held-out accuracy is measured by bench_match_eval --real.
//
// The catalogue: the shaders a person accepts for these photos and the ones they were mistaken
// for before the selection (grass photo -> cells, gravel photo -> grass, rock -> cracked_mud, ...),
// 24 samples each, built once per build tree under a lock (tests/support/catalogue.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <set>
#include <string>

#include "catalog/store.h"
#include "image/image.h"
#include "search/match.h"
#include "shaders/renderer.h"
#include "shaders/spec.h"
#include "tests/support/catalogue.h"

namespace proctex::search {
namespace {

namespace fs = std::filesystem;

const fs::path& photo_catalogue() {
  static const fs::path path = testing::locked_catalogue(
      PROCTEX_BINARY, "photo-match-catalog.sqlite",
      {{{"grass", "gravel", "stones", "bricks", "pavers", "stone_wall", "starfield", "granite", "cells",
         "cracked_mud", "cobblestones", "noise_stack", "cellular_blend", "peeling_paint"},
        24}},
      21);
  return path;
}

MatchResult match_photo(const std::string& name, long evaluations) {
  const Image photo = prepare_target(fs::path(PROCTEX_SHARED_DIR) / "textures" / name, "");
  catalog::Store store(photo_catalogue(), catalog::Store::Access::Read);
  MatchOptions o;
  o.refine.max_evaluations = evaluations;
  return match(photo, store, o);
}

// Mostly the material is chosen before the refinement, so fewer renders than the CLI's 300 do.
void expect_material(const std::string& photo, const std::set<std::string>& accepted, long evaluations = 150) {
  const MatchResult r = match_photo(photo, evaluations);
  EXPECT_TRUE(accepted.count(r.spec.shader)) << photo << " matched as " << r.spec.shader << ": " << r.to_json().dump();
  // Whatever the verdict, it is one of the three, and "good" only for the right material.
  EXPECT_TRUE(r.verdict == "good" || r.verdict == "approximate" || r.verdict == "no-match") << r.verdict;
  if (r.verdict == "good") {
    EXPECT_TRUE(accepted.count(r.spec.shader)) << photo;
  }
}

TEST(PhotoMatch, BrickPhotoIsBricks) { expect_material("brick.png", {"bricks"}); }
TEST(PhotoMatch, GrassPhotoIsGrass) { expect_material("grass.png", {"grass"}); }
// With the CLI's effort: the gravel lane needs its whole refinement to show crushed stone. Skipped
// until session 11: the selection preferred grass for this photo (v1: 0.46 against 0.38); with the
// shape statistics and the lawn grass shader (selection v6) gravel leads (0.61 against grass 0.09).
TEST(PhotoMatch, GravelPhotoIsGravelOrStones) { expect_material("gravel.png", {"gravel", "stones"}, 300); }
TEST(PhotoMatch, HubblePhotoIsAStarfield) { expect_material("hubble_deep_field.jpg", {"starfield"}); }

// On a photo most race lanes cannot be chosen: their selection probability is so far below the
// race leader's that they would lose even at similarity 1 (match.cpp, stage 3). Those lanes are
// not raced - no renders, not finalists - and the answer is the one of racing all twelve, for
// fewer renders; the lazy race on two threads, the full one on one.
TEST(PhotoMatch, LanesThatCannotBeChosenAreNotRacedAndTheAnswerStays) {
  const Image photo = prepare_target(fs::path(PROCTEX_SHARED_DIR) / "textures" / "brick.png", "");
  catalog::Store store(photo_catalogue(), catalog::Store::Access::Read);
  MatchOptions every, lazy;
  every.refine.max_evaluations = lazy.refine.max_evaluations = 150;
  every.race_every_lane = true;
  every.threads = 1;
  lazy.threads = 2;
  const MatchResult all = match(photo, store, every), some = match(photo, store, lazy);
  ASSERT_FALSE(some.pattern);
  EXPECT_EQ(some.spec.to_json(), all.spec.to_json()) << some.to_json().dump();
  EXPECT_EQ(some.similarity, all.similarity);
  int unraced = 0;
  const double chosen = std::log(some.similarity) + kSelectionWeight * std::log(some.probability);
  for (const auto& s : some.starts) {
    if (s.value("raced", true)) continue;
    ++unraced;
    EXPECT_EQ(s["evaluations"], 0) << s.dump();
    EXPECT_FALSE(s["finalist"].get<bool>()) << s.dump();
    EXPECT_LT(kSelectionWeight * std::log(std::max(s["selection_probability"].get<double>(), 1e-9)), chosen) << s.dump();
  }
  EXPECT_GE(unraced, 4) << some.to_json().dump();
  EXPECT_LT(some.evaluations, all.evaluations);
  for (const auto& s : all.starts) EXPECT_TRUE(s.value("raced", true)) << s.dump();
}

// A photographed wall has detail at every scale down to the pixel (split faces, grain). When the
// shader cannot put that detail into large stones, the similarity is best with many small stones
// (session 18: report and tune photos came back with stones 2-3x too small). Target: 8 courses
// with grain of deviation 0.12 (linear RGB) on top. With the stone faces' roughness pinned at 0 (the
// shader as it was) the match returns 20 courses; with it free, 8 (measured: with grain 0.08 also 8,
// with 0.16 - more than the roughest faces hold - 16). The CLI's effort: with 150 renders a
// grain of 0.08 came back at 24 courses.
TEST(PhotoMatch, FineDetailOnAStoneWallDoesNotShrinkItsStones) {
  Renderer renderer;
  RenderSettings size;
  size.width = size.height = 256;
  Image target = renderer.render(parse_spec_argument("stone_wall:courses=8,roughness=0,relief=0.6,seed=9101"), size);
  std::mt19937 grain(3);
  std::normal_distribution<float> noise(0.0f, 0.12f);  // per pixel, grey, in linear RGB
  for (int y = 0; y < target.height; ++y)
    for (int x = 0; x < target.width; ++x) {
      const float n = noise(grain);
      float* rgb = target.pixel(x, y);
      for (int c = 0; c < 3; ++c) rgb[c] = std::max(0.0f, rgb[c] + n);
    }
  catalog::Store store(photo_catalogue(), catalog::Store::Access::Read);
  MatchOptions o;
  o.shaders = {"stone_wall"};
  o.refine.max_evaluations = 300;
  const MatchResult r = match(target, store, o);
  const int courses = r.spec.params.at("courses").get<int>();
  EXPECT_GE(courses, 6) << r.spec.to_json().dump();
  EXPECT_LE(courses, 10) << r.spec.to_json().dump();
}

}  // namespace
}  // namespace proctex::search
