// Catalogue tests: real SQLite files, real renders (tiny settings so the suite stays fast).
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <csignal>
#include <fstream>
#include <random>
#include <thread>

#include "catalog/catalog.h"
#include "catalog/sqlite.h"
#include "catalog/thumbnail.h"
#include "core/error.h"
#include "metrics/metric.h"
#include "tests/support/run.h"
#include "tests/support/temp_dir.h"

namespace proctex::catalog {
namespace {

namespace fs = std::filesystem;
using proctex::testing::TempDir;

SamplingSettings tiny(int samples = 12) {
  SamplingSettings s;
  s.samples = samples;
  s.resolution = 64;
  s.screen_resolution = 64;
  s.thumbnail = 32;
  s.probes = 4;
  s.max_iterations = 2;
  return s;
}

BuildOptions options(const fs::path& db, std::vector<std::string> shaders, int samples = 12) {
  BuildOptions o;
  o.db = db;
  o.shaders = std::move(shaders);
  o.settings = tiny(samples);
  o.seed = 7;
  o.jobs = 2;
  return o;
}

std::string file_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out << bytes;
}

// Runs SQL on a file directly (what another tool or a damaged disk would do).
void raw_exec(const fs::path& db, const std::string& sql) {
  sql::Connection c(db, sql::Connection::Mode::ReadWrite);
  c.exec(sql);
}

std::map<std::string, std::string> content_hashes(const fs::path& db) {
  Store s(db, Store::Access::Read);
  std::map<std::string, std::string> out;
  for (const auto& sum : s.shaders()) out[sum.name] = sum.content_hash;
  return out;
}

// ---------------------------------------------------------------------------------------------
// Graph measures and settings

TEST(CatalogMath, KappaMatchesEquation43) {
  // Three vertices, similarities 0.5, 0.2, 0.8: distances 0.5, 0.8, 0.2 over |E| = 3 edges.
  const std::vector<double> s = {1, 0.5, 0.2, 0.5, 1, 0.8, 0.2, 0.8, 1};
  EXPECT_NEAR(kappa(s, 3, 1.0), (0.5 + 0.8 + 0.2) / 3.0, 1e-12);
  EXPECT_NEAR(kappa(s, 3, 2.0), std::sqrt(0.25 + 0.64 + 0.04) / 3.0, 1e-12);
}

TEST(CatalogMath, LambdaPruningRemovesTheRedundantVertex) {
  // 0 and 1 are near-duplicates; 2 and 3 are distinct. Removing one vertex must remove 0 or 1.
  const std::vector<double> s = {1, 0.95, 0.1, 0.1,  //
                                 0.95, 1, 0.12, 0.1,  //
                                 0.1, 0.12, 1, 0.05,  //
                                 0.1, 0.1, 0.05, 1};
  const auto keep3 = prune(s, 4, 3);
  EXPECT_EQ(keep3, (std::vector<int>{0, 2, 3}));
  // Eq 4.5 sums over all vertices: after the duplicate goes, vertex 0 (lambda 0.2) still has the
  // largest lambda, so the printed criterion drops the whole cluster - one reason coverage pruning
  // is the default (docs/catalog.md).
  EXPECT_EQ(prune(s, 4, 2), (std::vector<int>{2, 3}));
}

TEST(CatalogMath, CoveragePruningKeepsWhatServesTheReferences) {
  // References 0..2 are best served by vertex 0; reference 3 only by vertex 2; vertex 1 serves
  // nobody better than vertex 0: it is the one to drop.
  const std::vector<double> rs = {0.9, 0.8, 0.1,  //
                                  0.9, 0.85, 0.1,  //
                                  0.8, 0.7, 0.1,  //
                                  0.1, 0.1, 0.9};
  EXPECT_EQ(prune_coverage(rs, 4, 3, 2), (std::vector<int>{0, 2}));
}

TEST(CatalogSettings, ApplyValidatesAndHashChanges) {
  SamplingSettings s;
  const std::string h = s.hash(1);
  EXPECT_NE(h, s.hash(2)) << "the seed is part of the settings hash";
  s.apply("omega", "0.7");
  EXPECT_DOUBLE_EQ(s.omega, 0.7);
  EXPECT_NE(s.hash(1), h);
  SamplingSettings b = s;
  b.batch = 8;
  EXPECT_EQ(b.hash(1), s.hash(1)) << "launch size does not change results";
  EXPECT_THROW(s.apply("omegaa", "1"), UsageError);
  EXPECT_THROW(s.apply("max_iterations", "1.5"), UsageError);
  EXPECT_THROW(s.apply("samples", "many"), UsageError);
  SamplingSettings bad;
  bad.resolution = 100;
  EXPECT_THROW(bad.validate(), UsageError);
  bad = SamplingSettings{};
  bad.mode = "grid";
  EXPECT_THROW(bad.validate(), UsageError);
  EXPECT_EQ(SamplingSettings::from_json(s.to_json()).to_json(), s.to_json());
}

TEST(CatalogShards, ParseAndEqualCostsGoRoundRobinBySortedName) {
  EXPECT_EQ(Shard::parse("3/8").index, 3);
  EXPECT_EQ(Shard::parse("3/8").count, 8);
  for (const char* bad : {"0/2", "3/2", "1", "a/b", "1/0", "1/2x"}) EXPECT_THROW(Shard::parse(bad), UsageError) << bad;
  const std::vector<std::string> names = {"d", "a", "c", "b", "e"};
  EXPECT_EQ(shard_shaders(names, Shard::parse("1/2")), (std::vector<std::string>{"a", "c", "e"}));
  EXPECT_EQ(shard_shaders(names, Shard::parse("2/2")), (std::vector<std::string>{"b", "d"}));
  // Every shader lands in exactly one shard.
  std::multiset<std::string> all;
  for (int i = 1; i <= 3; ++i)
    for (const auto& n : shard_shaders(names, Shard{i, 3})) all.insert(n);
  EXPECT_EQ(all, std::multiset<std::string>(names.begin(), names.end()));
}

TEST(CatalogPaths, DefaultLocationHonoursEnvironment) {
  const char* old = std::getenv("PROCTEX_CATALOG");
  const std::string saved = old ? old : "";
  setenv("PROCTEX_CATALOG", "/tmp/x/cat.sqlite", 1);
  EXPECT_EQ(default_catalog_path(), fs::path("/tmp/x/cat.sqlite"));
  unsetenv("PROCTEX_CATALOG");
  EXPECT_EQ(default_catalog_path().filename(), "catalog.sqlite");
  if (old) setenv("PROCTEX_CATALOG", saved.c_str(), 1);
}

TEST(CatalogThumbnails, PngRoundTrip) {
  Image img(16, 8);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 16; ++x) {
      img.pixel(x, y)[0] = x / 15.0f;
      img.pixel(x, y)[1] = y / 7.0f;
      img.pixel(x, y)[2] = 0.5f;
    }
  const auto png = encode_png(img);
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png[1], 'P');
  const Image back = decode_png(png);
  ASSERT_EQ(back.width, 16);
  ASSERT_EQ(back.height, 8);
  for (size_t i = 0; i < img.pixels.size(); ++i) EXPECT_NEAR(back.pixels[i], img.pixels[i], 0.01f);
  EXPECT_THROW(decode_png(std::vector<unsigned char>{1, 2, 3}), Error);
}

// ---------------------------------------------------------------------------------------------
// Builds

TEST(CatalogBuild, SchemaAndContents) {
  TempDir dir;
  const fs::path db = dir / "cat.sqlite";
  const BuildReport r = build(options(db, {"checker", "stripes"}));
  ASSERT_EQ(r.shaders.size(), 2u);
  for (const auto& s : r.shaders) EXPECT_EQ(s.status, "built");

  sql::Connection c(db, sql::Connection::Mode::ReadOnly);
  EXPECT_EQ(c.scalar_int("PRAGMA user_version"), kSchemaVersion);
  EXPECT_EQ(c.scalar_int("PRAGMA application_id"), kApplicationId);
  EXPECT_EQ(c.scalar_text("PRAGMA journal_mode"), "wal");
  EXPECT_EQ(c.scalar_int("SELECT count(*) FROM shaders"), 2);
  EXPECT_EQ(c.scalar_int("SELECT count(*) FROM builds WHERE finished_at IS NOT NULL"), 1);

  Store store(db, Store::Access::Read);
  const auto& metric = metrics::default_metric();
  for (const char* name : {"checker", "stripes"}) {
    const ShaderCatalogue cat = store.load(name);
    const int n = static_cast<int>(cat.samples.size());
    ASSERT_GE(n, 2) << name;
    EXPECT_LE(n, 12) << name;
    const auto& decl = ShaderLibrary::builtin().get(name);
    EXPECT_EQ(cat.source_hash, decl.source_hash);
    for (const auto& s : cat.samples) {
      EXPECT_EQ(static_cast<int>(s.packed.size()), decl.packed_size);
      for (float u : s.unit) {
        EXPECT_GE(u, 0.0f);
        EXPECT_LE(u, 1.0f);
      }
      EXPECT_EQ(s.features.metric, metric.id());
      EXPECT_EQ(s.features.version, metric.version());
      EXPECT_EQ(s.features.values.size(), metric.feature_size());
      EXPECT_GE(s.smoothness, 0.0) << "adaptive mode stores H";
      EXPECT_EQ(decode_png(s.thumbnail).width, 32);
    }
    // Fully connected, weights are the metric's similarity of the stored features.
    EXPECT_NEAR(cat.edge(0, 1), metric.similarity(cat.samples[0].features.values, cat.samples[1].features.values), 1e-6);
    EXPECT_DOUBLE_EQ(cat.edge(0, 1), cat.edge(1, 0));
    EXPECT_FALSE(cat.pruned.empty());
    EXPECT_LE(cat.pruned.size(), static_cast<size_t>(n));
    for (int p : cat.pruned) EXPECT_LT(p, n);
    EXPECT_TRUE(store.consistency_problems(name).empty());
    const auto sum = store.summary(name).value();
    ASSERT_TRUE(sum.coverage.has_value());
    EXPECT_EQ(sum.coverage->probes, 4);
    EXPECT_GT(sum.coverage->mean, 0.0);
    EXPECT_LE(sum.coverage->max, 1.0);
    EXPECT_EQ(sum.seed, 7u);
    EXPECT_FALSE(sum.device.empty());
  }
  EXPECT_EQ(c.scalar_int("SELECT count(*) FROM edges e JOIN shaders s ON s.id = e.shader_id WHERE s.name = 'checker'"),
            [&] { Store s2(db, Store::Access::Read); const int n = s2.summary("checker")->samples; return int64_t(n) * (n - 1) / 2; }());
  // Float vectors are little-endian float32 BLOBs.
  auto q = c.prepare("SELECT length(vector) FROM features LIMIT 1");
  ASSERT_TRUE(q.step());
  EXPECT_EQ(q.column_int(0), static_cast<int64_t>(4 * metric.feature_size()));
  EXPECT_TRUE(store.integrity_problems().empty());
}

TEST(CatalogBuild, DeterministicAndShardsMergeToTheFullBuild) {
  TempDir dir;
  const std::vector<std::string> shaders = {"checker", "circle", "stripes"};
  build(options(dir / "full.sqlite", shaders));
  build(options(dir / "again.sqlite", shaders));
  EXPECT_EQ(content_hashes(dir / "full.sqlite"), content_hashes(dir / "again.sqlite"))
      << "same seed and sources give the same samples";
  {
    Store a(dir / "full.sqlite", Store::Access::Read), b(dir / "again.sqlite", Store::Access::Read);
    const auto ca = a.load("circle"), cb = b.load("circle");
    ASSERT_EQ(ca.samples.size(), cb.samples.size());
    for (size_t i = 0; i < ca.samples.size(); ++i) EXPECT_EQ(ca.samples[i].unit, cb.samples[i].unit);
  }
  auto o1 = options(dir / "s1.sqlite", shaders);
  o1.shard = Shard::parse("1/2");
  auto o2 = options(dir / "s2.sqlite", shaders);
  o2.shard = Shard::parse("2/2");
  // Split by the committed cost table: checker (8.1 s) alone, circle + stripes (5.9 s each).
  EXPECT_EQ(build(o1).shaders.size(), 1u);
  EXPECT_EQ(build(o2).shaders.size(), 2u);
  const MergeReport m = merge(dir / "merged.sqlite", {dir / "s1.sqlite", dir / "s2.sqlite"});
  EXPECT_EQ(m.added.size(), 3u);
  EXPECT_EQ(content_hashes(dir / "merged.sqlite"), content_hashes(dir / "full.sqlite"));
  // Merged rows equal the full build's rows, edges and thumbnails included.
  Store full(dir / "full.sqlite", Store::Access::Read), merged(dir / "merged.sqlite", Store::Access::Read);
  for (const auto& name : shaders) {
    const auto a = full.load(name), b = merged.load(name);
    EXPECT_EQ(a.edges, b.edges) << name;
    EXPECT_EQ(a.pruned, b.pruned) << name;
    ASSERT_EQ(a.samples.size(), b.samples.size());
    for (size_t i = 0; i < a.samples.size(); ++i) EXPECT_EQ(a.samples[i].thumbnail, b.samples[i].thumbnail);
  }
  // Merging again is a no-op, not a conflict.
  const MergeReport again = merge(dir / "merged.sqlite", {dir / "s1.sqlite", dir / "s2.sqlite"});
  EXPECT_TRUE(again.added.empty());
  EXPECT_EQ(again.unchanged.size(), 3u);
}

TEST(CatalogBuild, IncrementalSkipsUnchangedAndRebuildsChanged) {
  TempDir dir;
  const fs::path db = dir / "cat.sqlite";
  build(options(db, {"checker", "stripes"}));
  const auto before = content_hashes(db);
  const BuildReport again = build(options(db, {"checker", "stripes"}));
  for (const auto& s : again.shaders) EXPECT_EQ(s.status, "skipped") << s.shader;
  EXPECT_EQ(content_hashes(db), before);

  auto changed = options(db, {"checker"}, 10);
  const BuildReport r = build(changed);
  ASSERT_EQ(r.shaders.size(), 1u);
  EXPECT_EQ(r.shaders[0].status, "rebuilt");
  EXPECT_EQ(r.shaders[0].reason, "settings or seed changed");
  EXPECT_LE(r.shaders[0].samples, 10);
  EXPECT_EQ(content_hashes(db).at("stripes"), before.at("stripes")) << "other shaders untouched";

  changed.force = true;
  EXPECT_EQ(build(changed).shaders[0].reason, "forced");

  // A changed source (a user's shader folder) is detected as stale and rebuilt.
  ShaderLibrary lib = ShaderLibrary::builtin();
  ShaderDecl decl = lib.get("checker");
  decl.source += "\n// edited\n";
  decl.source_hash = stable_hash(decl.source);
  lib.add(decl);
  const auto info_json = info(db, lib);
  bool stale = false;
  for (const auto& s : info_json["shaders"])
    if (s["shader"] == "checker") stale = s["stale"].get<bool>();
  EXPECT_TRUE(stale);
  const BuildReport re = build(options(db, {"checker"}, 10), {}, lib);
  EXPECT_EQ(re.shaders[0].reason, "source changed");
}

TEST(CatalogBuild, UniformModeAndCoverage) {
  TempDir dir;
  auto o = options(dir / "u.sqlite", {"circle"});
  o.settings.mode = "uniform";
  const BuildReport r = build(o);
  EXPECT_EQ(r.shaders[0].samples, 12) << "uniform keeps exactly N";
  Store s(dir / "u.sqlite", Store::Access::Read);
  const auto cat = s.load("circle");
  for (const auto& smp : cat.samples) EXPECT_LT(smp.smoothness, 0.0) << "no H in uniform mode";
  ASSERT_TRUE(r.shaders[0].coverage.has_value());
  const Coverage& c = *r.shaders[0].coverage;
  EXPECT_LE(c.min, c.p10);
  EXPECT_LE(c.p10, c.median);
  EXPECT_LE(c.median, c.max);
}

TEST(CatalogBuild, ProgressEventsAndSmallShaderNeverExceedsN) {
  TempDir dir;
  int events = 0;
  double last = -1;
  auto o = options(dir / "p.sqlite", {"checker"}, 6);
  build(o, [&](const BuildEvent& e) {
    ++events;
    EXPECT_EQ(e.shader, "checker");
    EXPECT_GE(e.fraction, 0.0);
    last = e.fraction;
  });
  EXPECT_GT(events, 3);
  EXPECT_DOUBLE_EQ(last, 1.0);
  EXPECT_LE(Store(dir / "p.sqlite", Store::Access::Read).summary("checker")->samples, 6);
}

// ---------------------------------------------------------------------------------------------
// Bad input and faults: clear errors, and an existing file is never changed

TEST(CatalogFaults, UnknownShaderIsUsageErrorBeforeTouchingTheFile) {
  TempDir dir;
  EXPECT_THROW(build(options(dir / "x.sqlite", {"no_such_shader"})), UsageError);
  EXPECT_FALSE(fs::exists(dir / "x.sqlite"));
  EXPECT_THROW(select_shaders(ShaderLibrary::builtin(), "checker,nope"), UsageError);
  EXPECT_EQ(select_shaders(ShaderLibrary::builtin(), "all").size(), ShaderLibrary::builtin().names().size());
}

TEST(CatalogFaults, UnwritablePath) {
  TempDir dir;
  write_bytes(dir / "file", "x");
  try {
    build(options(dir / "file" / "cat.sqlite", {"checker"}));
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(e.message().find("cat.sqlite"), std::string::npos) << e.message();
    EXPECT_FALSE(e.hint().empty());
  }
  EXPECT_THROW(build(options(dir.path(), {"checker"})), Error) << "a folder is not a catalogue";
  EXPECT_THROW(Store(dir / "missing.sqlite", Store::Access::Read), Error);
}

TEST(CatalogFaults, NewerSchemaIsRefusedAndLeftUntouched) {
  TempDir dir;
  const fs::path db = dir / "cat.sqlite";
  build(options(db, {"checker"}, 6));
  raw_exec(db, "PRAGMA user_version = 99");
  // Checkpoint so the file holds everything and the comparison below sees the whole state.
  raw_exec(db, "PRAGMA wal_checkpoint(TRUNCATE)");
  const std::string bytes = file_bytes(db);
  try {
    build(options(db, {"checker"}, 6));
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(e.message().find("newer"), std::string::npos) << e.message();
  }
  EXPECT_THROW(Store(db, Store::Access::Read), Error);
  EXPECT_THROW(merge(dir / "out.sqlite", {db}), Error);
  EXPECT_EQ(file_bytes(db), bytes);
}

TEST(CatalogFaults, CorruptFilesAreRefusedAndLeftUntouched) {
  TempDir dir;
  // Random bytes.
  std::mt19937 rng(3);
  std::string noise(20000, '\0');
  for (auto& ch : noise) ch = static_cast<char>(rng());
  write_bytes(dir / "noise.sqlite", noise);
  EXPECT_THROW(build(options(dir / "noise.sqlite", {"checker"}, 6)), Error);
  EXPECT_THROW(info(dir / "noise.sqlite"), Error);
  EXPECT_EQ(file_bytes(dir / "noise.sqlite"), noise);

  // A real catalogue, truncated (a copy cut off mid-transfer).
  const fs::path good = dir / "good.sqlite";
  build(options(good, {"checker", "stripes"}, 8));
  raw_exec(good, "PRAGMA wal_checkpoint(TRUNCATE)");
  const std::string whole = file_bytes(good);
  ASSERT_GT(whole.size(), 8192u);
  const fs::path cut = dir / "cut.sqlite";
  write_bytes(cut, whole.substr(0, whole.size() / 2));
  const std::string cut_bytes = file_bytes(cut);
  EXPECT_THROW(build(options(cut, {"checker", "stripes", "circle"}, 8)), Error);
  EXPECT_EQ(file_bytes(cut), cut_bytes);
  const VerifyReport v = [&] {
    try {
      return verify(cut, {});
    } catch (const Error&) {
      VerifyReport r;
      r.ok = false;
      return r;
    }
  }();
  EXPECT_FALSE(v.ok) << "verify must not pass a truncated file";

  // Another application's SQLite database.
  const fs::path other = dir / "other.sqlite";
  raw_exec([&] { sql::Connection c(other, sql::Connection::Mode::Create); return other; }(),
           "CREATE TABLE t (x); INSERT INTO t VALUES (1)");
  const std::string other_bytes = file_bytes(other);
  try {
    build(options(other, {"checker"}, 6));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(e.message().find("not a proctex catalogue"), std::string::npos) << e.message();
  }
  EXPECT_EQ(file_bytes(other), other_bytes);
}

TEST(CatalogFaults, MergeConflictIsAnErrorAndWritesNothing) {
  TempDir dir;
  auto a = options(dir / "a.sqlite", {"checker"}, 6);
  auto b = options(dir / "b.sqlite", {"checker"}, 6);
  b.seed = 8;
  build(a);
  build(b);
  try {
    merge(dir / "out.sqlite", {dir / "a.sqlite", dir / "b.sqlite"});
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(e.message().find("checker"), std::string::npos) << e.message();
  }
  EXPECT_FALSE(fs::exists(dir / "out.sqlite"));
  // Conflict with what OUT already holds: OUT keeps its content.
  fs::copy_file(dir / "a.sqlite", dir / "out2.sqlite");
  const auto before = content_hashes(dir / "out2.sqlite");
  EXPECT_THROW(merge(dir / "out2.sqlite", {dir / "b.sqlite"}), Error);
  EXPECT_EQ(content_hashes(dir / "out2.sqlite"), before);
}

TEST(CatalogVerify, PassesFreshAndCatchesTampering) {
  TempDir dir;
  const fs::path db = dir / "cat.sqlite";
  build(options(db, {"circle", "stripes"}, 8));
  VerifyOptions vo;
  vo.samples_per_shader = 2;
  const VerifyReport ok = verify(db, vo);
  EXPECT_TRUE(ok.ok) << (ok.problems.empty() ? "" : ok.problems.front());
  ASSERT_EQ(ok.shaders.size(), 2u);
  for (const auto& s : ok.shaders) EXPECT_GT(s["min_similarity"].get<double>(), 0.99);

  // Replace a stored feature vector with another sample's: re-rendering exposes it.
  raw_exec(db,
           "UPDATE features SET vector = (SELECT f2.vector FROM features f2 JOIN shaders s ON s.id = f2.shader_id "
           "WHERE s.name = 'circle' AND f2.idx = 1) WHERE idx = 0 AND shader_id = (SELECT id FROM shaders WHERE name = 'circle')");
  const VerifyReport bad = verify(db, vo);
  EXPECT_FALSE(bad.ok);
  // Deleting edges breaks the full graph.
  raw_exec(db, "DELETE FROM edges WHERE a = 0 AND shader_id = (SELECT id FROM shaders WHERE name = 'stripes')");
  const VerifyReport bad2 = verify(db, vo);
  bool edge_problem = false;
  for (const auto& p : bad2.problems) edge_problem = edge_problem || p.find("edges") != std::string::npos;
  EXPECT_TRUE(edge_problem);
}

TEST(CatalogSheet, ContactSheetOfThumbnails) {
  TempDir dir;
  const fs::path db = dir / "cat.sqlite";
  build(options(db, {"stripes"}, 9));
  const int n = Store(db, Store::Access::Read).summary("stripes")->samples;
  const Image img = sheet(db, "stripes", "full", 3, 64);
  EXPECT_GT(img.width, 3 * 64);
  EXPECT_GT(img.height, ((n + 2) / 3) * 64);
  const Image pruned = sheet(db, "stripes", "pruned");
  EXPECT_GT(pruned.width, 0);
  EXPECT_THROW(sheet(db, "checker"), UsageError) << "not in this catalogue";
  EXPECT_THROW(sheet(db, "stripes", "tiny"), UsageError);
}

}  // namespace
}  // namespace proctex::catalog
