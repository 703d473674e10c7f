// Transformation tests: power-cost paths, the morph space, jump-edge storage (schema v2), morphs
// within and across shaders on tiny real catalogues (real PoCL renders, real SQLite files).
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include <fmt/format.h>

#include "catalog/catalog.h"
#include "catalog/sqlite.h"
#include "core/error.h"
#include "metrics/metric.h"
#include "shaders/library.h"
#include "tests/support/temp_dir.h"
#include "transform/jumps.h"
#include "transform/morph.h"
#include "transform/path.h"
#include "transform/space.h"

namespace proctex::transform {
namespace {

namespace fs = std::filesystem;
using proctex::testing::TempDir;

// ---------------------------------------------------------------------------------------------
// Paths (no device)

TEST(PowerPath, LargerPowerPrefersMoreSmallerSteps) {
  // 0 -> 2 directly (dissimilarity 0.8) or through 1 in two steps of 0.5.
  Graph g(3);
  g.add_edge(0, 2, 0.8);
  g.add_edge(0, 1, 0.5);
  g.add_edge(1, 2, 0.5);
  const auto p1 = shortest_path(g, 0, 2, 1.0);  // sum: 0.8 < 1.0
  ASSERT_TRUE(p1);
  EXPECT_EQ(p1->vertices, (std::vector<int>{0, 2}));
  EXPECT_NEAR(p1->cost, 0.8, 1e-12);
  const auto p3 = shortest_path(g, 0, 2, 3.0);  // 0.125 + 0.125 < 0.512
  ASSERT_TRUE(p3);
  EXPECT_EQ(p3->vertices, (std::vector<int>{0, 1, 2}));
  EXPECT_NEAR(p3->cost, std::cbrt(0.25), 1e-12);  // eq 5.1: (e1^n + e2^n)^(1/n)
}

TEST(PowerPath, UnreachableAndBadPower) {
  Graph g(3);
  g.add_edge(0, 1, 0.1);
  EXPECT_FALSE(shortest_path(g, 0, 2, 3.0));
  EXPECT_THROW(shortest_path(g, 0, 1, 0.5), UsageError);
}

TEST(MorphSpaceTest, DiscreteParametersMoveInWholeValues) {
  const ShaderDecl& decl = ShaderLibrary::builtin().get("bricks");
  const MorphSpace sp(decl);
  const ParamDecl* rows = decl.find("rows");
  ASSERT_NE(rows, nullptr);
  ASSERT_EQ(rows->type, ParamType::Int);
  auto a = decl.default_packed(), b = a;
  a[rows->offset] = rows->min;
  b[rows->offset] = rows->min + 10;
  EXPECT_EQ(sp.max_discrete_step(a, b), 10);
  for (int k = 0; k <= 20; ++k) {
    const auto m = sp.lerp(a, b, k / 20.0);
    EXPECT_EQ(m[rows->offset], std::round(m[rows->offset])) << "t = " << k / 20.0;
    EXPECT_GE(m[rows->offset], a[rows->offset]);
    EXPECT_LE(m[rows->offset], b[rows->offset]);
  }
  EXPECT_EQ(sp.lerp(a, b, 0), a);
  EXPECT_EQ(sp.lerp(a, b, 1), b);
}

// ---------------------------------------------------------------------------------------------
// A tiny catalogue shared by the tests below (built once: ~10 s).

catalog::SamplingSettings tiny() {
  catalog::SamplingSettings s;
  s.samples = 14;
  s.resolution = 64;
  s.screen_resolution = 64;
  s.thumbnail = 32;
  s.probes = 0;
  s.max_iterations = 1;
  return s;
}

LinkOptions quick_link() {
  LinkOptions o;
  o.jumps = 2;
  o.rounds = 1;
  o.evaluations = 12;
  o.resolution = 64;
  return o;
}

class Transform : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    catalog::BuildOptions o;
    o.db = db();
    o.shaders = {"bricks", "circle", "polkadots", "rectangle", "superellipse"};
    o.settings = tiny();
    o.seed = 5;
    o.jobs = 2;
    catalog::build(o);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static fs::path db() { return *dir_ / "cat.sqlite"; }
  // A copy of the shared catalogue that a test may change.
  static fs::path copy_db(const std::string& name) {
    catalog::Store(db(), catalog::Store::Access::Write);  // checkpoint the WAL into the file
    const fs::path p = *dir_ / name;
    fs::remove(p);
    fs::copy_file(db(), p);
    return p;
  }
  static TempDir* dir_;
  Renderer renderer_;
};
TempDir* Transform::dir_ = nullptr;

MorphOptions quick(int frames) {
  MorphOptions o;
  o.frames = frames;
  o.threshold = 0.8;
  o.max_depth = 3;
  o.max_renders = 120;
  o.jobs = 2;
  return o;
}

TextureSpec spec(const std::string& text) { return parse_spec_argument(text); }

void expect_same_texture(const TextureSpec& frame, const TextureSpec& input) {
  const ShaderDecl& decl = ShaderLibrary::builtin().get(input.shader);
  EXPECT_EQ(frame.shader, input.shader);
  EXPECT_EQ(resolve(decl, frame), resolve(decl, input));
  EXPECT_EQ(frame.seed, input.seed);
}

TEST_F(Transform, WithinShaderEndsOnTheInputsAndEveryEdgeMeetsTheThresholdOrIsReported) {
  const auto a = spec("bricks:rows=4,mortar=0.03,seed=3"), b = spec("bricks:rows=20,mortar=0.2,seed=3");
  catalog::Store store(db(), catalog::Store::Access::Read);
  const Morph m = plan({a, b}, store, renderer_, quick(24));
  ASSERT_EQ(m.frames.size(), 24u);
  expect_same_texture(m.frames.front().spec, a);
  expect_same_texture(m.frames.back().spec, b);
  EXPECT_EQ(m.frames.front().key, 0);
  EXPECT_EQ(m.frames.back().key, 1);
  EXPECT_EQ(m.jumps, 0);
  EXPECT_EQ(m.shaders, std::vector<std::string>{"bricks"});
  int reported = 0;
  for (size_t i = 0; i + 1 < m.path.size(); ++i) {
    if (m.path[i].similarity < 0.8) {
      EXPECT_FALSE(m.path[i].reached) << "edge " << i << " below the threshold but not reported";
      EXPECT_FALSE(m.path[i].note.empty());
      ++reported;
    } else {
      EXPECT_TRUE(m.path[i].reached);
    }
  }
  EXPECT_EQ(static_cast<int>(m.unreached().size()), reported);
  EXPECT_EQ(m.unreached_count(), reported);
  // Seed and domain fixed along the path; positions increase.
  const ShaderDecl& decl = ShaderLibrary::builtin().get("bricks");
  const ParamDecl* rows = decl.find("rows");
  for (size_t i = 0; i < m.frames.size(); ++i) {
    EXPECT_EQ(m.frames[i].spec.seed, 3u);
    const float r = resolve(decl, m.frames[i].spec)[rows->offset];
    EXPECT_EQ(r, std::round(r)) << "frame " << i << " has a non-integer row count";
    if (i > 0) {
      EXPECT_GE(m.frames[i].position, m.frames[i - 1].position);
    }
  }
}

TEST_F(Transform, KeyTexturesAppearInOrder) {
  const std::vector<TextureSpec> keys = {spec("bricks:rows=6,seed=1"), spec("bricks:rows=12,mortar=0.15,seed=1"),
                                         spec("bricks:rows=16,seed=1")};
  catalog::Store store(db(), catalog::Store::Access::Read);
  const Morph m = plan(keys, store, renderer_, quick(30));
  ASSERT_EQ(m.frames.size(), 30u);
  std::vector<int> seen;
  for (const auto& f : m.frames)
    if (f.key >= 0) {
      seen.push_back(f.key);
    }
  ASSERT_EQ(seen, (std::vector<int>{0, 1, 2}));
  for (const auto& f : m.frames)
    if (f.key >= 0) expect_same_texture(f.spec, keys[f.key]);
}

TEST_F(Transform, FramesAreEvenInPerceptualDistanceAndBeatLinearInterpolation) {
  // Continuous parameters whose look changes unevenly along a straight line: even perceptual
  // spacing must lower the largest step. (When a whole step of an integer dominates, both
  // sequences contain the same step; see DiscreteParametersChangeOneWholeStepAtATime.)
  const auto a = spec("bricks:mortar=0.02,wear=0,seed=2"), b = spec("bricks:mortar=0.4,wear=1,seed=2");
  catalog::Store store(db(), catalog::Store::Access::Read);
  Morph m = plan({a, b}, store, renderer_, quick(32));
  m.quality = measure(m.frames, renderer_, m.resolution, 2);
  auto lin = linear_frames({a, b}, 32, renderer_.library());
  ASSERT_EQ(lin.size(), 32u);
  expect_same_texture(lin.front().spec, a);
  expect_same_texture(lin.back().spec, b);
  m.linear = measure(lin, renderer_, m.resolution, 2);
  EXPECT_EQ(m.quality->frames, 32);
  EXPECT_GT(m.quality->layout_mean, 0.0);
  EXPECT_LT(m.quality->max_dissimilarity, m.linear->max_dissimilarity)
      << "morph " << m.quality->to_json() << " linear " << m.linear->to_json();
  EXPECT_TRUE(m.quality_json()["beats_linear_on_max"].get<bool>());
}

TEST_F(Transform, DiscreteParametersChangeOneWholeStepAtATime) {
  const auto a = spec("bricks:rows=3,mortar=0.03,seed=2"), b = spec("bricks:rows=13,mortar=0.3,seed=2");
  catalog::Store store(db(), catalog::Store::Access::Read);
  const Morph m = plan({a, b}, store, renderer_, quick(30));
  const ShaderDecl& decl = ShaderLibrary::builtin().get("bricks");
  const int rows = decl.find("rows")->offset;
  // Every whole step is cut out as its own edge (a pure step: nothing else changes across it).
  const MorphSpace sp(decl);
  int steps = 0;
  for (size_t i = 0; i + 1 < m.path.size(); ++i)
    if (sp.max_discrete_step(m.path[i].packed, m.path[i + 1].packed) > 0) {
      ++steps;
      EXPECT_EQ(sp.max_discrete_step(m.path[i].packed, m.path[i + 1].packed), 1);
      EXPECT_LT(sp.max_continuous_difference(m.path[i].packed, m.path[i + 1].packed), 1e-3);
    }
  EXPECT_EQ(steps, 10);
  // With enough frames, each frame step crosses at most one whole step.
  for (size_t i = 1; i < m.frames.size(); ++i) {
    const float r0 = resolve(decl, m.frames[i - 1].spec)[rows], r1 = resolve(decl, m.frames[i].spec)[rows];
    EXPECT_LE(std::fabs(r1 - r0), 1.0f) << "frames " << i - 1 << " -> " << i;
  }
}

TEST_F(Transform, TooFewFramesAndBadInputsAreUsageErrors) {
  catalog::Store store(db(), catalog::Store::Access::Read);
  EXPECT_THROW(plan({spec("bricks")}, store, renderer_, quick(10)), UsageError);
  EXPECT_THROW(plan({spec("bricks"), spec("bricks:rows=9")}, store, renderer_, quick(1)), UsageError);
  // A shader that is not catalogued: a clear error naming the fix.
  try {
    plan({spec("marble"), spec("marble:seed=4")}, store, renderer_, quick(10));
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.message()).find("not in catalogue"), std::string::npos) << e.message();
  }
}

TEST_F(Transform, UnreachableShadersGiveAClearError) {
  catalog::Store store(db(), catalog::Store::Access::Read);
  try {
    plan({spec("polkadots"), spec("circle")}, store, renderer_, quick(10));
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.message()).find("no jump edges connect"), std::string::npos) << e.message();
    EXPECT_NE(e.hint().find("catalog link --shaders polkadots,circle"), std::string::npos) << e.hint();
  }
}

TEST_F(Transform, CrossShaderSequenceUsesAJumpEdge) {
  const fs::path p = copy_db("jump.sqlite");
  {
    catalog::Store store(p, catalog::Store::Access::Write);
    const auto pairs = choose_pairs(store, {"rectangle", "superellipse"}, quick_link());
    ASSERT_EQ(pairs.size(), 1u);
    const auto r = link(store, pairs, quick_link(), renderer_);
    ASSERT_EQ(r.pairs.size(), 1u);
    const auto jumps = store.jumps("rectangle");
    ASSERT_EQ(jumps.size(), 2u);
    for (const auto& j : jumps) {
      EXPECT_EQ(j.shader_a, "rectangle");
      EXPECT_EQ(j.shader_b, "superellipse");
      EXPECT_GT(j.similarity, 0.0);
      // The stored weight is the similarity of the stored features.
      EXPECT_NEAR(metrics::default_metric().similarity(j.features_a, j.features_b), j.similarity, 1e-9);
    }
  }
  catalog::Store store(p, catalog::Store::Access::Read);
  const auto a = spec("rectangle:width=0.5,height=0.5"), b = spec("superellipse:exponent=2");
  MorphOptions o = quick(20);
  o.dissolve = 2;
  const Morph m = plan({a, b}, store, renderer_, o);
  ASSERT_EQ(m.frames.size(), 20u);
  EXPECT_EQ(m.jumps, 1);
  EXPECT_EQ(m.shaders, (std::vector<std::string>{"rectangle", "superellipse"}));
  expect_same_texture(m.frames.front().spec, a);
  expect_same_texture(m.frames.back().spec, b);
  int jump_frames = 0, dissolves = 0;
  for (size_t i = 1; i < m.frames.size(); ++i) {
    jump_frames += m.frames[i].jump;
    dissolves += m.frames[i].blend_to.has_value();
    if (!m.frames[i].blend_to && !m.frames[i].jump && m.frames[i - 1].blend_to == std::nullopt) {
      EXPECT_EQ(m.frames[i].spec.shader, m.frames[i - 1].spec.shader) << "shader changes only at the jump";
    }
  }
  EXPECT_EQ(jump_frames, 1);
  // --dissolve K is the least number of cross-faded frames; a dissolve gets more when its measured
  // perceptual length calls for them. Blend weights rise along the cross-fade.
  EXPECT_GE(dissolves, 2);
  for (size_t i = 1; i < m.frames.size(); ++i)
    if (m.frames[i].blend_to && m.frames[i - 1].blend_to) {
      EXPECT_GT(m.frames[i].blend, m.frames[i - 1].blend) << "frame " << i;
    }
  // Subdivision never crosses the jump edge: the waypoints on both sides keep their shaders.
  for (size_t i = 0; i + 1 < m.path.size(); ++i)
    if (m.path[i].shader != m.path[i + 1].shader) {
      EXPECT_TRUE(m.path[i].jump);
    }
}

TEST(Dissolve, BlendsSitAtEqualPerceptualDistancesAlongTheCurve) {
  // Two sample intervals of lengths 3 and 1: one frame halfway in length (2) is 2/3 into the first
  // interval, at blend (2/3) / 2; three frames at lengths 1, 2, 3 end exactly at the first sample.
  const std::vector<double> curve = {0.0, 3.0, 4.0};
  const auto one = dissolve_blends(curve, 1);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_NEAR(one[0], 1.0 / 3.0, 1e-12);
  const auto three = dissolve_blends(curve, 3);
  ASSERT_EQ(three.size(), 3u);
  EXPECT_NEAR(three[0], 1.0 / 6.0, 1e-12);
  EXPECT_NEAR(three[1], 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(three[2], 0.5, 1e-12);
  EXPECT_TRUE(dissolve_blends(curve, 0).empty());
}

TEST_F(Transform, CrossShaderMorphBeatsThePlainCrossFade) {
  // Issue 7: the morph must beat naive interpolation on the largest adjacent step, across shaders
  // too (the naive sequence there is a cross-fade with equal pixel weights).
  const fs::path p = copy_db("crossfade.sqlite");
  {
    catalog::Store store(p, catalog::Store::Access::Write);
    link(store, {{"circle", "rectangle"}}, quick_link(), renderer_);
  }
  catalog::Store store(p, catalog::Store::Access::Read);
  const auto a = spec("rectangle:width=0.7,height=0.3"), b = spec("circle:size=0.5");
  MorphOptions o = quick(16);
  o.dissolve = 2;
  o.anchor_evaluations = 24;
  Morph m = plan({a, b}, store, renderer_, o);
  EXPECT_EQ(m.jumps, 1);
  expect_same_texture(m.frames.front().spec, a);
  expect_same_texture(m.frames.back().spec, b);
  m.quality = measure(m.frames, renderer_, m.resolution, 2);
  auto lin = linear_frames({a, b}, 16, renderer_.library());
  m.linear = measure(lin, renderer_, m.resolution, 2);
  EXPECT_LT(m.quality->max_dissimilarity, m.linear->max_dissimilarity)
      << "morph " << m.quality->to_json() << " cross-fade " << m.linear->to_json() << " " << m.stats.dump();
  // Anchored jumps were found for both keys, each at least as alike as the best start it tried and
  // weighted by the similarity of its stored features.
  ASSERT_EQ(m.stats["anchors"].size(), 2u);
  for (const auto& an : m.stats["anchors"]) EXPECT_GE(an["similarity"].get<double>(), an["info"]["start"]["best_start"].get<double>());
  const auto cat = store.load("circle", false);
  const ShaderDecl& rect = renderer_.library().get("rectangle");
  const auto pa = resolve(rect, a);
  const auto fa = render_features(renderer_, rect, {pa}, {a.seed}, m.resolution, 1).front();
  const auto e = anchor_jump("rectangle", pa, a.seed, fa, cat, renderer_.library().get("circle").default_packed(), a.seed,
                             renderer_, {.evaluations = 24});
  EXPECT_EQ(e.shader_b, "circle");
  EXPECT_NEAR(metrics::default_metric().similarity(e.features_a, e.features_b), e.similarity, 1e-9);
}

TEST_F(Transform, ConnectiveShaderCarriesRectangleToCircle) {
  // Only rectangle - superellipse and superellipse - circle are linked: the path has to pass
  // through the superellipse (thesis fig 5-12).
  const fs::path p = copy_db("connective.sqlite");
  {
    catalog::Store store(p, catalog::Store::Access::Write);
    link(store, {{"rectangle", "superellipse"}, {"circle", "superellipse"}}, quick_link(), renderer_);
  }
  catalog::Store store(p, catalog::Store::Access::Read);
  const Morph m = plan({spec("rectangle"), spec("circle")}, store, renderer_, quick(24));
  EXPECT_EQ(m.shaders, (std::vector<std::string>{"rectangle", "superellipse", "circle"}));
  EXPECT_EQ(m.jumps, 2);
  // Without connective shaders the same request has no direct edge.
  MorphOptions direct = quick(24);
  direct.connective = false;
  EXPECT_THROW(plan({spec("rectangle"), spec("circle")}, store, renderer_, direct), Error);
}

// ---------------------------------------------------------------------------------------------
// Jump-edge storage: schema v2 and its migration

TEST_F(Transform, JumpEdgesRoundTripAndGoWithARebuiltShader) {
  const fs::path p = copy_db("store.sqlite");
  catalog::Store store(p, catalog::Store::Access::Write);
  EXPECT_EQ(store.schema_version(), catalog::kSchemaVersion);
  catalog::JumpEdge e;
  e.shader_a = "superellipse";  // given out of name order: stored as rectangle - superellipse
  e.shader_b = "rectangle";
  const auto sa = store.load("superellipse", false), ra = store.load("rectangle", false);
  e.packed_a = sa.samples[0].packed;
  e.packed_b = ra.samples[1].packed;
  e.features_a = sa.samples[0].features;
  e.features_b = ra.samples[1].features;
  e.seed_a = 11;
  e.seed_b = 22;
  e.similarity = 0.25;
  store.write_jumps("superellipse", "rectangle", {e});
  store.write_jumps("superellipse", "rectangle", {e});  // replaces, never duplicates
  auto j = store.jumps();
  ASSERT_EQ(j.size(), 1u);
  EXPECT_EQ(j[0].shader_a, "rectangle");
  EXPECT_EQ(j[0].packed_a, ra.samples[1].packed);
  EXPECT_EQ(j[0].packed_b, sa.samples[0].packed);
  EXPECT_EQ(j[0].seed_a, 22u);
  EXPECT_EQ(j[0].features_b.values, sa.samples[0].features.values);
  EXPECT_DOUBLE_EQ(j[0].similarity, 0.25);
  EXPECT_TRUE(store.jumps("circle").empty());
  EXPECT_THROW(store.write_jumps("rectangle", "marble", {}), UsageError);
  EXPECT_TRUE(store.integrity_problems().empty());
  // Rewriting a shader (a rebuild) drops the jump edges found from its old samples.
  store.write(store.load("rectangle"), "test", 0.0);
  EXPECT_TRUE(store.jumps().empty());
}

// A hand-made jump edge between sample `i` of `a` and sample `j` of `b` (storage tests need no link).
catalog::JumpEdge hand_edge(catalog::Store& store, const std::string& a, const std::string& b, int i, int j, double s) {
  const auto ca = store.load(a, false), cb = store.load(b, false);
  catalog::JumpEdge e;
  e.shader_a = a;
  e.shader_b = b;
  e.packed_a = ca.samples.at(i).packed;
  e.packed_b = cb.samples.at(j).packed;
  e.features_a = ca.samples.at(i).features;
  e.features_b = cb.samples.at(j).features;
  e.similarity = s;
  return e;
}

std::vector<std::string> edge_keys(catalog::Store& store) {
  std::vector<std::string> out;
  for (const auto& e : store.jumps())
    out.push_back(fmt::format("{}-{} {} {}", e.shader_a, e.shader_b, e.similarity, e.packed_a.front()));
  return out;
}

TEST_F(Transform, MergeCopiesJumpEdgesAndNeverReplacesOutsOwn) {
  // Two shards, each linking a pair of its own shaders; a third file of schema v1 (no jumps table).
  const fs::path s1 = copy_db("shard1.sqlite"), s2 = copy_db("shard2.sqlite"), v1 = copy_db("shard-v1.sqlite");
  std::vector<std::string> want;
  {
    catalog::Store a(s1, catalog::Store::Access::Write);
    a.remove("bricks");
    a.remove("polkadots");
    a.write_jumps("rectangle", "superellipse", {hand_edge(a, "rectangle", "superellipse", 0, 1, 0.4),
                                                 hand_edge(a, "rectangle", "superellipse", 2, 3, 0.3)});
    a.write_jumps("circle", "superellipse", {hand_edge(a, "circle", "superellipse", 1, 1, 0.5)});
    catalog::Store b(s2, catalog::Store::Access::Write);
    b.remove("rectangle");
    b.write_jumps("bricks", "polkadots", {hand_edge(b, "bricks", "polkadots", 4, 5, 0.2)});
    want = edge_keys(a);
    for (const auto& k : edge_keys(b)) want.push_back(k);
    std::sort(want.begin(), want.end());
  }
  {
    catalog::sql::Connection c(v1, catalog::sql::Connection::Mode::ReadWrite);
    c.exec("DROP TABLE jumps; PRAGMA user_version = 1");
  }
  const fs::path out = *dir_ / "merged-jumps.sqlite";
  fs::remove(out);
  const auto r = catalog::merge(out, {s1, s2, v1});
  EXPECT_EQ(r.jump_edges, 4);
  EXPECT_EQ(r.linked, (std::vector<std::string>{"circle-superellipse", "rectangle-superellipse", "bricks-polkadots"}));
  {
    catalog::Store m(out, catalog::Store::Access::Read);
    auto got = edge_keys(m);
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, want);
    EXPECT_TRUE(m.integrity_problems().empty());
    // The copied edges carry their vectors and features unchanged.
    catalog::Store a(s1, catalog::Store::Access::Read);
    const auto ja = a.jumps("rectangle"), jm = m.jumps("rectangle");
    ASSERT_EQ(ja.size(), jm.size());
    for (size_t i = 0; i < ja.size(); ++i) {
      EXPECT_EQ(ja[i].packed_b, jm[i].packed_b);
      EXPECT_EQ(ja[i].features_a.values, jm[i].features_a.values);
    }
  }
  // OUT already links rectangle - superellipse its own way: a merge keeps that, adds nothing twice.
  {
    catalog::Store m(out, catalog::Store::Access::Write);
    m.write_jumps("rectangle", "superellipse", {hand_edge(m, "rectangle", "superellipse", 5, 6, 0.7)});
  }
  std::vector<std::string> before;
  {
    catalog::Store m(out, catalog::Store::Access::Read);
    before = edge_keys(m);
  }
  const auto again = catalog::merge(out, {s1, s2});
  EXPECT_TRUE(again.added.empty());
  EXPECT_TRUE(again.linked.empty());
  EXPECT_EQ(again.jump_edges, 0);
  catalog::Store m(out, catalog::Store::Access::Read);
  EXPECT_EQ(edge_keys(m), before);
  ASSERT_EQ(m.jumps("rectangle").size(), 1u);
  EXPECT_DOUBLE_EQ(m.jumps("rectangle").front().similarity, 0.7);
}

TEST_F(Transform, VersionOneFilesStayReadableAndMigrate) {
  // A v1 file is exactly a v2 file without the jumps table.
  const fs::path p = copy_db("v1.sqlite");
  std::map<std::string, std::string> before;
  {
    catalog::sql::Connection c(p, catalog::sql::Connection::Mode::ReadWrite);
    c.exec("DROP TABLE jumps; PRAGMA user_version = 1");
  }
  {
    catalog::Store r(p, catalog::Store::Access::Read);
    EXPECT_EQ(r.schema_version(), 1);
    EXPECT_TRUE(r.jumps().empty());
    for (const auto& s : r.shaders()) before[s.name] = s.content_hash;
    EXPECT_EQ(static_cast<int>(r.load("bricks").samples.size()), r.summary("bricks")->samples);
  }
  {
    catalog::sql::Connection c(p, catalog::sql::Connection::Mode::ReadOnly);
    EXPECT_EQ(c.scalar_int("PRAGMA user_version"), 1) << "reading must not migrate";
  }
  catalog::Store w(p, catalog::Store::Access::Write);
  EXPECT_EQ(w.schema_version(), catalog::kSchemaVersion);
  for (const auto& s : w.shaders()) EXPECT_EQ(before[s.name], s.content_hash) << s.name;
  for (const auto& s : w.shaders()) EXPECT_TRUE(w.consistency_problems(s.name).empty()) << s.name;
  EXPECT_TRUE(w.integrity_problems().empty());
}

}  // namespace
}  // namespace proctex::transform
