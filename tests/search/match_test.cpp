// proctex match (issue 6) as a user relies on it: recovery of deterministic targets, the 4-pointed
// star, a failed match reported as no-match, clear errors for bad inputs and catalogues, and the
// command's options and outputs.
//
// The catalogue: 7 shaders (4 at 200 samples, 3 at 24), built once and kept in the build tree
// (build/tests/match-test-catalog.sqlite). ctest runs every test in its own process, so a per-process
// fixture would rebuild it for each test; instead every process runs the incremental build under a
// file lock, which builds it the first time (~40 s on an idle 2-core machine) and skips every
// unchanged shader afterwards (a shader source or metric change rebuilds just what changed).
// Targets are rendered with seeds >= 9000; the catalogue's render seeds come from its own stream.
#include <mutex>

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <tuple>

#include <nlohmann/json.hpp>

#include "catalog/catalog.h"
#include "catalog/store.h"
#include "core/error.h"
#include "image/image.h"
#include "metrics/metric.h"
#include "search/match.h"
#include "shaders/library.h"
#include "shaders/renderer.h"
#include "shaders/spec.h"
#include "tests/support/catalogue.h"
#include "tests/support/run.h"
#include "tests/support/temp_dir.h"

namespace proctex::search {
namespace {

namespace fs = std::filesystem;
using testing::run_proctex;
using testing::TempDir;

// bricks and star are the recovery targets; rectangle and circle are the shapes a 4-pointed star
// was confused with (the thesis's failure). They are built at the thesis's density (200 samples;
// a user's default catalogue holds 48 since session 17): at 24 or 64 samples the nearest star
// sample is too far and a refined circle wins against the 4-pointed star (measured: circle 0.60-0.62, star 0.56-0.59).
// Against the whole library this target still goes to circle (S 0.61) with 48 samples and with the
// four shapes at 200 (session 17): this 7-shader catalogue does not protect a user from that.
// checker, clouds and stripes are cheap, unrelated textures that must lose, at 24 samples.
const std::vector<std::string> kDense = {"bricks", "circle", "rectangle", "star"};
const std::vector<std::string> kSparse = {"checker", "clouds", "stripes"};
constexpr size_t kShaderCount = 7;
constexpr uint64_t kCatalogueSeed = 11;

fs::path catalogue_path() { return fs::path(PROCTEX_BINARY).parent_path().parent_path() / "tests" / "match-test-catalog.sqlite"; }

// Builds (first time) or checks (afterwards, about a second) the shared catalogue.
const fs::path& shared_catalogue() {
  static const fs::path path = testing::locked_catalogue(
      PROCTEX_BINARY, catalogue_path().filename().string(), {{kDense, 200}, {kSparse, 24}}, kCatalogueSeed);
  return path;
}

// A consistent single-file copy of the shared catalogue that a test may change.
fs::path copy_catalogue(const fs::path& to) {
  sqlite3* h = nullptr;
  EXPECT_EQ(sqlite3_open_v2(shared_catalogue().c_str(), &h, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_busy_timeout(h, 5000);
  char* err = nullptr;
  const std::string sql = "VACUUM INTO '" + to.string() + "'";
  EXPECT_EQ(sqlite3_exec(h, sql.c_str(), nullptr, nullptr, &err), SQLITE_OK) << (err ? err : "");
  sqlite3_free(err);
  sqlite3_close(h);
  return to;
}

void exec_sql(const fs::path& db, const std::string& sql) {
  sqlite3* h = nullptr;
  ASSERT_EQ(sqlite3_open(db.c_str(), &h), SQLITE_OK);
  char* err = nullptr;
  EXPECT_EQ(sqlite3_exec(h, sql.c_str(), nullptr, nullptr, &err), SQLITE_OK) << (err ? err : "");
  EXPECT_EQ(sqlite3_changes(h), 1) << sql;
  sqlite3_free(err);
  sqlite3_close(h);
}

Image render(const TextureSpec& spec, int size = 256) {
  Renderer renderer;
  RenderSettings s;
  s.width = s.height = size;
  return renderer.render(spec, s);
}
Image render(const std::string& spec, int size = 256) { return render(parse_spec_argument(spec), size); }

// Small enough that a match over the 7-shader catalogue takes a few seconds.
MatchOptions quick() {
  MatchOptions o;
  o.starts = 3;
  o.refine.max_evaluations = 150;
  return o;
}

MatchResult match_image(const Image& target, const MatchOptions& options = quick()) {
  catalog::Store store(shared_catalogue(), catalog::Store::Access::Read);
  return match(target, store, options);
}

// A parameter of the result spec (spec_from_packed writes every parameter out).
const nlohmann::json& param(const MatchResult& r, const std::string& name) {
  static const nlohmann::json missing;
  const auto it = r.spec.params.find(name);
  return it == r.spec.params.end() ? missing : it->second;
}

std::string describe(const MatchResult& r) { return r.to_json().dump(); }

// ---------------------------------------------------------------------------------------------
// Recovery

// Bricks with variation, wear and roughness at 0: the layout (courses, brick ratio, joint width,
// bond) and the brick colour do not depend on the seed; only the mortar keeps a faint noise texture
// (+-25 % of its colour) that the seed moves. These parameters must come back: whole values exactly;
// ratio within 0.15 (range 1..6) and the joint width within 25 % (a 0.15-course joint is ~5 px at
// 256 px and 7 courses, so 25 % is about a pixel); colours within 0.06 per linear channel.
// With the CLI's default effort (300 renders per start): with half of it every bricks lane of the
// race ends in an English-bond alias (ratio 5.2) that the exact polish cannot leave.
TEST(Match, RecoversTheParametersOfADeterministicBricksTarget) {
  const Image target = render(
      "bricks:rows=7,ratio=2.6,mortar=0.15,brick=(0.45,0.16,0.08),mortar_color=(0.7,0.7,0.66),"
      "variation=0,wear=0,roughness=0,bond=running,seed=9001");
  const MatchResult r = match_image(target, MatchOptions{});
  ASSERT_EQ(r.spec.shader, "bricks") << describe(r);
  EXPECT_EQ(param(r, "rows"), 7) << describe(r);
  EXPECT_EQ(param(r, "bond"), "running") << describe(r);
  EXPECT_EQ(param(r, "vertical"), false) << describe(r);
  EXPECT_NEAR(param(r, "ratio").get<double>(), 2.6, 0.15) << describe(r);
  EXPECT_NEAR(param(r, "mortar").get<double>(), 0.15, 0.25 * 0.15) << describe(r);
  const std::vector<double> brick = {0.45, 0.16, 0.08}, mortar = {0.7, 0.7, 0.66};
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(param(r, "brick")[c].get<double>(), brick[c], 0.06) << "channel " << c << describe(r);
    EXPECT_NEAR(param(r, "mortar_color")[c].get<double>(), mortar[c], 0.06) << "channel " << c << describe(r);
  }
  EXPECT_EQ(r.verdict, "good") << describe(r);
}

// The thesis's failure (a non-integer point count, then the wrong shader) must be a success: the
// 4-pointed star is the star shader with exactly 4 points, written as a whole number.
TEST(Match, FourPointedStarIsAStarWithExactlyFourPoints) {
  const Image target =
      render("star:points=4,size=0.75,inner=0.4,rotation=20,fg=(0.9,0.85,0.2),bg=(0.1,0.15,0.35),seed=9002");
  const MatchResult r = match_image(target);
  ASSERT_EQ(r.spec.shader, "star") << describe(r);
  EXPECT_TRUE(param(r, "points").is_number_integer()) << describe(r);
  EXPECT_EQ(param(r, "points"), 4) << describe(r);
  // The star shader is deterministic: its size, shape and colours come back too, each within 10 %
  // of the parameter's declared range (size 0.1..0.98, inner 0.1..0.95, colours 0..1). The rotation
  // is not asserted: the statistical metrics hardly see the phase of a 4-fold star.
  EXPECT_NEAR(param(r, "size").get<double>(), 0.75, 0.1 * 0.88) << describe(r);
  EXPECT_NEAR(param(r, "inner").get<double>(), 0.4, 0.1 * 0.85) << describe(r);
  const std::vector<double> fg = {0.9, 0.85, 0.2}, bg = {0.1, 0.15, 0.35};
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(param(r, "fg")[c].get<double>(), fg[c], 0.1) << "channel " << c << describe(r);
    EXPECT_NEAR(param(r, "bg")[c].get<double>(), bg[c], 0.1) << "channel " << c << describe(r);
  }
  EXPECT_EQ(r.verdict, "good") << describe(r);
  // A deterministic shape leads the finalists on a clean pattern: the selection (a classifier of
  // photographed materials) weighs only a share in the final choice.
  EXPECT_TRUE(r.pattern) << describe(r);
  EXPECT_LT(r.selection_share, 1.0) << describe(r);
}

// A star with n points turned by 360/n is the same star (shaders/shape/star.cl declares
// `rotation ... period=360/points`, session 14): a 12-pointed star at 148.6 degrees is the one at
// 28.6, 58.6, 88.6 and 118.6. The match reports the canonical value, reduced into [0, 30), within
// 2% of the range (3.6 degrees) of 28.6; before, it reported whichever period its search ended in
// (this star, benchmark target 6 of session 14 at 58.6, came back at 118.6; an 8-pointed one at
// 44.99 at 0.0), and a plain comparison called an exact image wrong.
TEST(Match, AStarTurnedByItsSymmetryComesBackAsTheCanonicalRotation) {
  const Image target = render(
      "star:points=12,size=0.3656,inner=0.2118,rotation=148.62,softness=0.47,fg=(0.3937,0.0877,0.607),"
      "bg=(0.1555,0.9583,0.8756),seed=9006");
  const MatchResult r = match_image(target, MatchOptions{});
  ASSERT_EQ(r.spec.shader, "star") << describe(r);
  EXPECT_EQ(param(r, "points"), 12) << describe(r);
  const double rotation = param(r, "rotation").get<double>();
  EXPECT_GE(rotation, 0.0) << describe(r);
  EXPECT_LT(rotation, 30.0) << describe(r);
  const double off = std::fmod(std::fabs(rotation - 28.62), 30.0);  // modulo the period, the shorter way
  EXPECT_LT(std::min(off, 30.0 - off), 0.02 * 180) << describe(r);
  EXPECT_LT(r.image_rmse, 0.005) << describe(r);
}

// Issue 12's exactness: a clean shape comes back with every continuous parameter within 2% of its
// declared range and its colours within 0.02, so that its render is the target's image (RMS
// difference under 1% of the colour range). Against the catalogue of 48 samples per shader the
// statistics left such a ring a few % off (RMS 0.014; docs/match-evaluation.md); with this test
// catalogue's 200 circles they already come close, and the align stage (metrics/aligned.h) must
// keep it that way.
TEST(Match, AThinSoftRingComesBackWithinTwoPercent) {
  const Image target = render("circle:size=0.66,ring=0.88,softness=0.03,fg=(0.08,0.5,0.12),bg=(0.29,0.05,0.52),seed=9005");
  const MatchResult r = match_image(target);
  ASSERT_EQ(r.spec.shader, "circle") << describe(r);
  const std::vector<std::tuple<std::string, double, double>> expected = {
      {"size", 0.66, 0.9}, {"ring", 0.88, 1.0}, {"softness", 0.03, 0.5}};
  for (const auto& [name, value, range] : expected)
    EXPECT_NEAR(param(r, name).get<double>(), value, 0.02 * range) << name << describe(r);
  const std::vector<double> fg = {0.08, 0.5, 0.12}, bg = {0.29, 0.05, 0.52};
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(param(r, "fg")[c].get<double>(), fg[c], 0.02) << "channel " << c << describe(r);
    EXPECT_NEAR(param(r, "bg")[c].get<double>(), bg[c], 0.02) << "channel " << c << describe(r);
  }
  const Image matched = render(r.spec);
  double sum = 0;
  for (size_t i = 0; i < matched.pixels.size(); ++i) sum += std::pow(matched.pixels[i] - target.pixels[i], 2);
  EXPECT_LT(std::sqrt(sum / double(matched.pixels.size())), 0.01) << describe(r);
  EXPECT_EQ(r.verdict, "good") << describe(r);
}

// A soft ring in colours the align stage got wrong (synthetic target 11 of bench_match_eval
// --targets 53, session 21): the best try registered at RGB RMS 0.067, and the pixel polish was
// only handed tries within 0.05, so the match stayed there (S 0.75, `approximate`). At the shader's
// origin, after a least-squares colour fit, the polish admits starts up to 0.1 and reaches the
// target's pixels. This ring's blur is wider than its band, so its parameters are not all fixed by
// the image (PixelPolish.ASoftRingComesBackToTheSameImageAndItsIdentifiableShape): the pixels are
// what must come back.
TEST(Match, ASoftRingInTheWrongColoursIsPolishedToTheTargetsPixels) {
  const Image target = render("circle:size=0.8391,ring=0.5933,softness=0.2992,fg=(0.5026,0.5397,0.9958),"
                              "bg=(0.0022,0.628,0.0781),seed=9011");
  const MatchResult r = match_image(target);
  ASSERT_EQ(r.spec.shader, "circle") << describe(r);
  const Image matched = render(r.spec);
  double sum = 0;
  for (size_t i = 0; i < matched.pixels.size(); ++i) sum += std::pow(matched.pixels[i] - target.pixels[i], 2);
  EXPECT_LT(std::sqrt(sum / double(matched.pixels.size())), 0.005) << describe(r);
  EXPECT_EQ(r.verdict, "good") << describe(r);
}

// Soft stripes at 30 degrees: the statistics leave the duty and the softness loose along a ridge
// (before the align stage the match ended at duty 0.72 in swapped colours, softness 0.62: a
// visibly other texture). The complementary duty in swapped colours is the same image shifted
// (stripes at 30 degrees are not periodic on the image, so only the overlap compares), and is
// accepted as such.
TEST(Match, SoftStripesComeBackWithinTwoPercentUpToTheirAlias) {
  const Image target = render("stripes:stripes=7,angle=30,duty=0.3,softness=0.5,wave=0,color_a=(0.8,0.3,0.1),seed=9006");
  const MatchResult r = match_image(target, MatchOptions{});  // the CLI's default effort
  ASSERT_EQ(r.spec.shader, "stripes") << describe(r);
  EXPECT_NEAR(param(r, "angle").get<double>(), 30, 0.02 * 180) << describe(r);
  EXPECT_NEAR(param(r, "softness").get<double>(), 0.5, 0.02) << describe(r);
  const double duty = param(r, "duty").get<double>();
  EXPECT_LT(std::min(std::fabs(duty - 0.3), std::fabs(duty - 0.7)), 0.02 * 0.9) << describe(r);
  // The image: the best shift within a stripe period (~37 px), RMS on the overlap.
  const Image matched = render(r.spec);
  double best = 1e30;
  for (int dy = -20; dy <= 20; ++dy)
    for (int dx = -20; dx <= 20; ++dx) {
      double sum = 0;
      size_t count = 0;
      for (int y = std::max(0, -dy); y < std::min(256, 256 - dy); ++y)
        for (int x = std::max(0, -dx); x < std::min(256, 256 - dx); ++x, ++count)
          for (int c = 0; c < 3; ++c) sum += std::pow(matched.pixel(x + dx, y + dy)[c] - target.pixel(x, y)[c], 2);
      best = std::min(best, std::sqrt(sum / (3.0 * count)));
    }
  EXPECT_LT(best, 0.01) << describe(r);
  // Such a result is the target's pattern: the match says so (the statistical similarity rated
  // this alias 0.68 and called it "approximate"), and the registered RMS difference it reports
  // is the one measured here (up to the sub-pixel shift it cannot take).
  EXPECT_TRUE(r.pixel_exact) << describe(r);
  EXPECT_NEAR(r.image_rmse, best, 0.003) << describe(r);
  EXPECT_EQ(r.verdict, "good") << describe(r);
}

// Fine, strongly waved stripes (the deterministic benchmark's target 7: 63 stripes, a 4 px period,
// a wave of 0.82 at 3.15 waves) come back with every parameter within 2% of its range. Before
// session 24 the match ended with 57 stripes 22 degrees off (S 0.18): the magnitude polish ran at
// 128 px, where these stripes average to nearly flat, and started only from the race's end point.
TEST(Match, FineWavyStripesComeBackExactly) {
  const Image target = render(
      "stripes:stripes=63,angle=88.48,duty=0.153,softness=0.511,wave=0.824,wave_frequency=3.153,"
      "color_a=(0.035,0.469,0.146),color_b=(0.403,0.395,0.840),seed=9008");
  const MatchResult r = match_image(target, MatchOptions{});  // the CLI's default effort
  ASSERT_EQ(r.spec.shader, "stripes") << describe(r);
  EXPECT_EQ(param(r, "stripes").get<int>(), 63) << describe(r);
  EXPECT_NEAR(param(r, "angle").get<double>(), 88.48, 0.02 * 180) << describe(r);
  EXPECT_NEAR(param(r, "wave").get<double>(), 0.824, 0.02) << describe(r);
  EXPECT_NEAR(param(r, "wave_frequency").get<double>(), 3.153, 0.02 * 11) << describe(r);
  EXPECT_NEAR(param(r, "softness").get<double>(), 0.511, 0.02) << describe(r);
  EXPECT_TRUE(r.pixel_exact) << describe(r);
  EXPECT_EQ(r.verdict, "good") << describe(r);
}

// --candidates M screens only the M shaders whose best catalogue sample is structurally closest
// (a scan of stored features, no rendering); the match comes from one of them. A bricks target
// keeps bricks among 2 of the 7 shaders (the others: shapes, checker, clouds, stripes).
TEST(Match, OnlyTheStructurallyClosestShadersAreScreened) {
  const Image target = render("bricks:rows=8,ratio=2.5,seed=9005");
  MatchOptions o = quick();
  o.candidate_shaders = 2;
  const MatchResult r = match_image(target, o);
  ASSERT_EQ(r.candidates.size(), 2u) << describe(r);
  const auto kept = [&](const std::string& name) {
    return std::any_of(r.candidates.begin(), r.candidates.end(), [&](const auto& c) { return c.shader == name; });
  };
  EXPECT_TRUE(kept("bricks")) << describe(r);
  EXPECT_TRUE(kept(r.spec.shader)) << describe(r);
  for (const auto& start : r.starts) EXPECT_TRUE(kept(start["shader"])) << describe(r);
}

// The reported similarity is the similarity of the returned spec's render to the target: rendering
// the spec again and comparing gives the same number (the spec is complete, seed included).
TEST(Match, ReportedSimilarityIsReproducibleFromTheSpec) {
  const Image target = render("checker:squares=5,color_a=(0.8,0.3,0.1),color_b=(0.1,0.2,0.5),seed=9003");
  const MatchResult r = match_image(target);
  ASSERT_FALSE(r.spec.shader.empty());
  const metrics::Metric& m = metrics::default_metric();
  const double again = m.similarity(m.features(target, 256), m.features(render(r.spec), 256));
  EXPECT_NEAR(again, r.similarity, 1e-6) << describe(r);
  EXPECT_EQ(r.verdict, r.pixel_exact ? "good" : verdict_for(r.similarity, r.probability, r.pattern && !r.visibly_other, r.pattern_similarity));
}

// Targets no shader of the library can express. A verdict only means something if a failed match
// says so (thesis: a large residual flags the failure).
Image white_noise(int size, uint64_t seed) {
  // Independent uniform RGB values per pixel (portable SplitMix64 stream).
  uint64_t state = seed;
  auto next = [&] {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return float((z ^ (z >> 31)) >> 40) / float(1 << 24);
  };
  Image img(size, size);
  for (float& v : img.pixels) v = next();
  return img;
}

TEST(Match, ATargetNoShaderCanExpressIsNoMatch) {
  // (Blocky noise - random colours on a 32x32 grid - is not such a target: bricks with a stack
  // bond, square bricks and full colour variation express it, measured S 0.31 "approximate"; nor
  // is a dark/light split with gradients: a 2-square checker is half of it, S 0.35.)
  // Pixel noise repeated every 32 px is a clean pattern (all its energy at multiples of 8 cycles),
  // so its verdict also asks the similarity without the spectrum (kApproximateMatch, match.h).
  Image tiled_noise(256, 256);
  const Image tile = white_noise(32, 9006);
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x)
      for (int c = 0; c < 3; ++c) tiled_noise.pixels[3 * (y * 256 + x) + c] = tile.pixels[3 * ((y % 32) * 32 + x % 32) + c];
  for (const auto& [name, target] : {std::pair<std::string, Image>{"pixel noise", white_noise(256, 9004)},
                                     std::pair<std::string, Image>{"tiled pixel noise", tiled_noise}}) {
    const MatchResult r = match_image(target);
    EXPECT_EQ(r.verdict, "no-match") << name << ": " << describe(r);
    EXPECT_LT(r.similarity, kApproximateMatch) << name;
    EXPECT_LT(r.pattern_similarity, kApproximateMatch) << name;
    EXPECT_FALSE(r.spec.shader.empty()) << name << ": the best attempt is still reported";
  }
}

// A clean pattern answered by the right shader with a detail off is what a person calls
// approximate, though the spectrum - which wants each peak in its very frequency bin - rates it as
// unrelated: 43 wavy stripes matched with their wave pinned to another strength and frequency.
TEST(Match, ACleanPatternWithItsPeaksElsewhereIsApproximateNotNoMatch) {
  const Image target = render(
      "stripes:stripes=43,angle=81.1,duty=0.42,softness=0.2,wave=0.3,wave_frequency=2.73,"
      "color_a=(0.72,0.71,0.05),color_b=(0.52,0.23,0.72),seed=9007");
  MatchOptions o = quick();
  o.shaders = {"stripes"};
  o.fixed["wave"] = 0.8;
  o.fixed["wave_frequency"] = 4.3;
  const MatchResult r = match_image(target, o);
  ASSERT_EQ(r.spec.shader, "stripes");
  ASSERT_TRUE(r.pattern);
  ASSERT_LT(r.similarity, kApproximateMatch) << "the whole similarity alone would say no-match: " << describe(r);
  EXPECT_GE(r.pattern_similarity, kApproximateMatch) << describe(r);
  EXPECT_EQ(r.verdict, "approximate") << describe(r);
}

// "Pixel-exact" is relative to what the target shows: on a nearly flat target (faint hairlines on a
// plain ground) a flat image is within RMS 0.005 of it and misses everything a person sees.
TEST(Match, PixelExactOnAFaintTargetNeedsACloserReproduction) {
  Image faint(256, 256), bold(256, 256);
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x) {
      const bool line = (x + 3 * y) % 29 == 0;  // thin diagonal lines on 1 pixel in 29
      for (int c = 0; c < 3; ++c) {
        faint.pixel(x, y)[c] = 0.3f + (line ? 0.025f : 0.0f);
        bold.pixel(x, y)[c] = line ? 0.9f : 0.1f;
      }
    }
  // the flat ground alone is within the absolute limit of it, yet shows none of the lines
  double flat_rmse = 0;
  for (int i = 0; i < 256 * 256 * 3; ++i) flat_rmse += std::pow(faint.pixels[i] - 0.3f, 2);
  flat_rmse = std::sqrt(flat_rmse / (256 * 256 * 3));
  EXPECT_LT(flat_rmse, kPixelExactRmse);
  EXPECT_LT(pixel_exact_limit(faint), flat_rmse / 5) << "a flat image would pass as the faint lines";
  EXPECT_DOUBLE_EQ(pixel_exact_limit(bold), kPixelExactRmse) << "a contrasted pattern keeps the absolute limit";
}

// ---------------------------------------------------------------------------------------------
// Speed without another answer (issue 12, session 13)

// The race's lanes run on several threads; each lane is its own search, so the result - spec,
// similarity, every lane's renders and similarities - is the one of a race on one thread.
// The same answer, similarity, render count, and the same lanes with the same similarities, renders
// and refinement.
void expect_same_match(const MatchResult& a, const MatchResult& b) {
  EXPECT_EQ(a.spec.to_json(), b.spec.to_json());
  EXPECT_EQ(a.similarity, b.similarity);
  EXPECT_EQ(a.evaluations, b.evaluations);
  ASSERT_EQ(a.starts.size(), b.starts.size());
  for (size_t i = 0; i < a.starts.size(); ++i) {
    for (const char* key : {"shader", "screened_similarity", "colour_similarity", "refined_similarity_coarse",
                            "evaluations", "refined", "refined_similarity"})
      EXPECT_EQ(a.starts[i].value(key, nlohmann::json()), b.starts[i].value(key, nlohmann::json())) << i << " " << key;
  }
}

TEST(Match, ParallelRaceGivesTheSameResultAsOneThread) {
  const Image target = render("clouds:seed=9021");
  MatchOptions one = quick(), two = quick();
  one.threads = 1;
  two.threads = 2;
  const MatchResult a = match_image(target, one), b = match_image(target, two);
  expect_same_match(a, b);
  // And the screening before it: the candidates in the selection's order, each with the same best
  // screened similarity (it also passed with the screening on the race's threads, session 14).
  ASSERT_EQ(a.candidates.size(), b.candidates.size());
  for (size_t i = 0; i < a.candidates.size(); ++i) {
    EXPECT_EQ(a.candidates[i].shader, b.candidates[i].shader) << i;
    EXPECT_EQ(a.candidates[i].screened, b.candidates[i].screened) << i;
  }
}

// With the race on several threads the progress a service shows must still only count up: each
// lane's own count added to the finished lanes' total went back and forth between two lanes (a
// job's live count fell from 193 to 179 in JobsPriority, session 13).
TEST(Match, ProgressCountOnlyGrowsDuringAParallelRace) {
  const Image target = render("clouds:seed=9021");
  MatchOptions two = quick();
  two.threads = 2;
  catalog::Store store(shared_catalogue(), catalog::Store::Access::Read);
  long last = 0, reports = 0, went_back = 0;
  std::mutex m;
  match(target, store, two, [&](const MatchProgress& p) {
    std::lock_guard lock(m);
    ++reports;
    if (p.evaluations < last) ++went_back;
    last = std::max(last, p.evaluations);
  });
  EXPECT_GT(reports, 10);
  EXPECT_EQ(went_back, 0) << "of " << reports << " progress reports";
}

// A finalist that cannot win the final choice (log S + log P with S <= 1: its log P is below the
// score a refined finalist already reached) is not refined further. On a non-pattern target the
// answer is the one of refining every finalist, for fewer renders, and every finalist left
// unrefined could not have been chosen. (The target needs a selection sure enough to rule a
// finalist out: selection v8 gives these clouds P 0.70 on the 7-shader catalogue; v6's rougher
// clouds of seed 9022, P 0.46 under v8, ruled none out.)
TEST(Match, FinalistsThatCannotWinAreNotRefinedAndTheAnswerStays) {
  // Fine clouds: a spread spectrum, not a clean pattern (the default clouds' few big blobs are).
  const Image target = render("clouds:scale=8,roughness=0.6,seed=9030");
  MatchOptions every = quick(), lazy = quick();
  every.refine_every_finalist = true;
  // Every lane raced in both: the lanes the race leaves out would otherwise change the finalists
  // (PhotoMatch.LanesThatCannotBeChosenAreNotRacedAndTheAnswerStays).
  every.race_every_lane = lazy.race_every_lane = true;
  const MatchResult all = match_image(target, every), some = match_image(target, lazy);
  ASSERT_FALSE(some.pattern) << describe(some);
  EXPECT_EQ(some.spec.to_json(), all.spec.to_json()) << describe(some);
  EXPECT_EQ(some.similarity, all.similarity);
  int unrefined = 0;
  const double chosen = std::log(some.similarity) + kSelectionWeight * std::log(some.probability);
  for (const auto& s : some.starts) {
    if (!s.value("finalist", false) || s.value("refined", true)) continue;
    ++unrefined;
    EXPECT_LE(kSelectionWeight * std::log(std::max(s["selection_probability"].get<double>(), 1e-9)), chosen) << s.dump();
  }
  EXPECT_GE(unrefined, 1) << describe(some);
  EXPECT_LT(some.evaluations, all.evaluations);
  for (const auto& s : all.starts) EXPECT_TRUE(s.value("refined", true)) << s.dump();
}

// On a photo-like target the finalists are refined two at a time, the second speculatively (the
// first's score may rule it out: then its refinement is undone). The result is the one of refining
// them one after the other: the same finalists left unrefined, the same renders.
TEST(Match, FinalistsRefinedTogetherGiveTheSameResultAsOneAfterTheOther) {
  const Image target = render("clouds:scale=8,roughness=0.6,seed=9030");
  MatchOptions one = quick(), two = quick();
  one.threads = 1;
  two.threads = 2;
  one.race_every_lane = two.race_every_lane = true;  // more finalists that cannot win (test above)
  const MatchResult a = match_image(target, one), b = match_image(target, two);
  ASSERT_FALSE(b.pattern) << describe(b);
  expect_same_match(a, b);
  int unrefined = 0;
  for (const auto& s : b.starts) unrefined += s.value("finalist", false) && !s.value("refined", true);
  EXPECT_GE(unrefined, 1) << "nothing ruled out: the undo is not exercised; " << describe(b);
}

// On a clean pattern, the exact polish of a finalist whose shader is not deterministic is skipped
// when its point could not change the final choice (kPolishGain in match.cpp; session 14: most
// of a clean-pattern photo's polish time went to such finalists, never the answer). The answer is
// the one of polishing every finalist, for fewer renders; deterministic finalists are polished.
TEST(Match, PolishesThatCannotChangeTheChoiceAreSkippedAndTheAnswerStays) {
  // The default clouds' few big blobs: a clean pattern by its spectrum, from a seed-driven shader.
  const Image target = render("clouds:seed=9023");
  MatchOptions every = quick(), lazy = quick();
  every.polish_every_finalist = true;
  const MatchResult all = match_image(target, every), some = match_image(target, lazy);
  ASSERT_TRUE(some.pattern) << describe(some);
  EXPECT_EQ(some.spec.to_json(), all.spec.to_json()) << describe(some);
  EXPECT_EQ(some.similarity, all.similarity);
  int skipped = 0;
  for (const auto& s : some.starts) {
    if (!s.contains("polish") || !s["polish"].contains("skipped")) continue;
    if (s["polish"]["skipped"] != "cannot change the final choice") continue;
    ++skipped;
    EXPECT_EQ(s["polish"]["deterministic"], false) << s.dump();
    EXPECT_LT(s["refined_similarity"].get<double>(), kCertainMatch) << s.dump();
  }
  EXPECT_GE(skipped, 1) << describe(some);
  EXPECT_LT(some.evaluations, all.evaluations);
  // Its most similar finalist is seed-driven, so the selection keeps its whole weight (session 20:
  // photos of parquet, slate roofs and curtains are clean patterns by their spectrum too, and the
  // reduced share let flexible look-alikes win there).
  const nlohmann::json* top = nullptr;
  for (const auto& s : some.starts)
    if (s.value("finalist", false) && (!top || s["refined_similarity"] > (*top)["refined_similarity"])) top = &s;
  ASSERT_NE(top, nullptr);
  EXPECT_EQ((*top)["polish"]["deterministic"], false) << top->dump();
  EXPECT_EQ(some.selection_share, 1.0) << describe(some);
  for (const auto& s : all.starts) {
    const bool skipped_in_all = s.contains("polish") && s["polish"].contains("skipped") &&
                                s["polish"]["skipped"] == "cannot change the final choice";
    EXPECT_FALSE(skipped_in_all) << s.dump();
  }
}

// ---------------------------------------------------------------------------------------------
// The command: options, outputs and errors

class MatchCli : public ::testing::Test {
 protected:
  TempDir dir;
  std::string path(const std::string& name) const { return (dir / name).string(); }
  testing::RunResult run(const std::string& args) { return run_proctex("match " + args, dir.path()); }
  // Saves a target image into the scratch folder.
  std::string target(const std::string& spec, int size = 256) {
    const std::string p = path("target.png");
    save_image(render(spec, size), p);
    return p;
  }
  std::string db() const { return shared_catalogue().string(); }
  // Outputs a failed command must not leave behind.
  const std::string outputs = " -o '" + path("r.json") + "' --render '" + path("r.png") + "' --compare '" + path("c.png") + "'";
  void expect_nothing_written() const {
    for (const char* f : {"r.json", "r.png", "c.png"}) EXPECT_FALSE(fs::exists(dir / f)) << f;
  }
  // One line on stderr, "proctex: error: ...", naming what is wrong; non-zero exit.
  void expect_clean_error(const testing::RunResult& r, const std::string& mentions) const {
    EXPECT_NE(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err.rfind("proctex: error: ", 0), 0u) << r.err;
    EXPECT_EQ(testing::line_count(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(mentions), std::string::npos) << "expected '" << mentions << "' in: " << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    expect_nothing_written();
  }
};

const char* kQuick = " --starts 2 --evaluations 60";

TEST_F(MatchCli, JsonResultRenderAndCompare) {
  const std::string t = target("bricks:rows=9,ratio=3,mortar=0.1,variation=0.2,wear=0.1,roughness=0.2,seed=9010");
  const auto r = run(t + " --db '" + db() + "'" + kQuick + " --json" + outputs + " --size 96");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key : {"spec", "similarity", "verdict", "metrics", "evaluations", "timings", "catalogue"})
    EXPECT_TRUE(j.contains(key)) << key << " missing: " << r.out;
  EXPECT_EQ(nlohmann::json::parse(testing::read_text(path("r.json"))), j) << "-o writes what --json prints";

  // The spec is a complete texture spec: it renders, and the render is what --render wrote.
  const TextureSpec spec = TextureSpec::from_json(j["spec"]);
  EXPECT_TRUE(ShaderLibrary::builtin().find(spec.shader)) << j["spec"];
  const Image written = load_image(path("r.png"));
  ASSERT_EQ(written.width, 96);
  ASSERT_EQ(written.height, 96);
  const Image again = render(spec, 96);
  double worst = 0;
  for (size_t i = 0; i < again.pixels.size(); ++i)
    worst = std::max(worst, double(std::fabs(linear_to_srgb(again.pixels[i]) - linear_to_srgb(written.pixels[i]))));
  EXPECT_LE(worst, 1.0 / 255 + 1e-4) << "--render is the spec rendered at --size (8-bit sRGB)";

  // Similarity in (0, 1], the documented verdict thresholds, timings and the catalogue's identity.
  const double s = j["similarity"];
  EXPECT_GT(s, 0.0);
  EXPECT_LE(s, 1.0);
  // "good" also needs the selection to find the material likely (search/match.h).
  const double p = j["selection_probability"];
  EXPECT_GE(p, 0.0);
  EXPECT_LE(p, 1.0);
  const bool pattern = j["pattern"];
  const double without_spectrum = j["pattern_similarity"].is_null() ? -1.0 : j["pattern_similarity"].get<double>();
  EXPECT_EQ(pattern, !j["pattern_similarity"].is_null()) << "the similarity without the spectrum is given for clean patterns";
  EXPECT_EQ(j["verdict"], (pattern && s >= kCertainMatch) || (s >= 0.5 && p >= kGoodProbability) ? "good"
                         : s >= 0.25 || without_spectrum >= 0.25                 ? "approximate"
                                                                                 : "no-match");
  EXPECT_GT(j["timings"]["total"].get<double>(), 0.0);
  // The race is part of the local stage (the rest is the finalists' refinement).
  EXPECT_GT(j["timings"]["race"].get<double>(), 0.0);
  EXPECT_LE(j["timings"]["race"].get<double>(), j["timings"]["local"].get<double>());
  EXPECT_EQ(j["catalogue"]["path"], db());
  EXPECT_EQ(j["catalogue"]["shaders"].size(), kShaderCount);
  EXPECT_EQ(j["catalogue"]["metric"], metrics::default_metric().id());
  EXPECT_EQ(j["catalogue"]["metric_version"], metrics::default_metric().version());
  EXPECT_EQ(j["stopped_early"], false);

  // Side by side: target and match in one image, wider than tall.
  const Image cmp = load_image(path("c.png"));
  EXPECT_GT(cmp.width, cmp.height);
  EXPECT_GE(cmp.width, 2 * 96);
}

TEST_F(MatchCli, HumanSummaryNamesTheShaderAndWhatWasWritten) {
  const std::string t = target("star:points=6,size=0.6,seed=9011");
  const auto r = run(t + " --db '" + db() + "'" + kQuick + " -o '" + path("r.json") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(testing::read_text(path("r.json")));
  EXPECT_NE(r.out.find(j["spec"]["shader"].get<std::string>()), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(j["verdict"].get<std::string>()), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(path("r.json")), std::string::npos) << r.out;
}

TEST_F(MatchCli, FixPinsParametersInTheResult) {
  // The target has 7 courses in a running bond; the user insists on 5 courses and a stack bond.
  const std::string t = target("bricks:rows=7,variation=0,wear=0,roughness=0,seed=9012");
  const auto r = run(t + " --db '" + db() + "' --shaders bricks --fix rows=5 --fix bond=stack" + kQuick + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["spec"]["shader"], "bricks");
  EXPECT_EQ(j["spec"]["params"]["rows"], 5) << r.out;
  EXPECT_EQ(j["spec"]["params"]["bond"], "stack") << r.out;
}

TEST_F(MatchCli, FixWithAnOutOfRangeValueIsAUsageError) {
  const std::string t = target("bricks:seed=9013");
  expect_clean_error(run(t + " --db '" + db() + "' --shaders bricks --fix rows=1000" + outputs), "rows");
}

TEST_F(MatchCli, FixOfAParameterNoShaderHasIsAUsageError) {
  // A typo must not be ignored silently: the user believes the parameter is pinned.
  const std::string t = target("bricks:seed=9015");
  expect_clean_error(run(t + " --db '" + db() + "' --fix rowz=5" + outputs), "rowz");
}

TEST_F(MatchCli, EvaluationBudgetStopsEarlyWithTheBestSoFar) {
  const std::string t = target("circle:seed=9014");
  const auto full = run(t + " --db '" + db() + "' --starts 2 --evaluations 150 --json");
  ASSERT_EQ(full.exit_code, 0) << full.err;
  const auto r = run(t + " --db '" + db() + "' --starts 2 --evaluations 150 --budget 5 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out), jf = nlohmann::json::parse(full.out);
  EXPECT_EQ(j["stopped_early"], true) << r.out;
  EXPECT_EQ(jf["stopped_early"], false) << full.out;
  EXPECT_FALSE(j["spec"]["shader"].get<std::string>().empty());
  EXPECT_GT(j["similarity"].get<double>(), 0.0);
  EXPECT_LT(j["evaluations"].get<long>(), jf["evaluations"].get<long>() / 2) << "budget run: " << j["evaluations"]
                                                                              << ", unlimited: " << jf["evaluations"];
}

TEST_F(MatchCli, TimeBudgetStopsEarly) {
  const std::string t = target("clouds:seed=9015");
  const auto r = run(t + " --db '" + db() + "' --budget 0.01s --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["stopped_early"], true) << r.out;
}

TEST_F(MatchCli, UnreadableImageIsAClearError) {
  { std::ofstream(path("photo.png")) << "this is not a PNG file"; }
  expect_clean_error(run(path("photo.png") + " --db '" + db() + "'" + outputs), "photo.png");
  expect_clean_error(run(path("missing.png") + " --db '" + db() + "'" + outputs), "missing.png");
}

TEST_F(MatchCli, TinyImageIsAClearError) {
  const std::string t = target("checker", 31);
  expect_clean_error(run(t + " --db '" + db() + "'" + outputs), "32");
  // Large enough as a file, but cropped below 32 pixels.
  const std::string big = target("checker", 128);
  expect_clean_error(run(big + " --crop 0,0,20,100 --db '" + db() + "'" + outputs), "32");
}

TEST_F(MatchCli, MissingCatalogueIsAClearErrorNamingTheBuildCommand) {
  const std::string t = target("checker", 64);
  const auto r = run(t + " --db '" + path("nowhere.sqlite") + "'" + outputs);
  expect_clean_error(r, "nowhere.sqlite");
  EXPECT_NE(r.err.find("proctex catalog build"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "nowhere.sqlite")) << "match must not create a catalogue";
}

TEST_F(MatchCli, EmptyCatalogueIsAClearError) {
  catalog::Store(dir / "empty.sqlite", catalog::Store::Access::Write);  // a valid catalogue, no shader
  const std::string t = target("checker", 64);
  const auto r = run(t + " --db '" + path("empty.sqlite") + "'" + outputs);
  expect_clean_error(r, "empty.sqlite");
  EXPECT_NE(r.err.find("proctex catalog build"), std::string::npos) << r.err;
}

TEST_F(MatchCli, StaleMetricVersionIsAClearErrorNamingTheRebuildCommand) {
  const fs::path stale = copy_catalogue(dir / "stale.sqlite");
  exec_sql(stale, "UPDATE shaders SET metric_version = metric_version - 1 WHERE name = 'circle'");
  const std::string t = target("checker", 64);
  const auto before = testing::read_text(stale);
  const auto r = run(t + " --db '" + stale.string() + "'" + outputs);
  expect_clean_error(r, "stale");
  EXPECT_NE(r.err.find("circle"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("proctex catalog build --db " + stale.string()), std::string::npos) << r.err;
  EXPECT_EQ(testing::read_text(stale), before) << "the catalogue is left as it was";
}

}  // namespace
}  // namespace proctex::search
