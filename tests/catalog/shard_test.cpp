// Balanced shards, measured costs (schema v3) and the merge agreement checks: real builds into real
// SQLite files, tiny settings.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <random>

#include "catalog/catalog.h"
#include "catalog/shard.h"
#include "catalog/sqlite.h"
#include "core/error.h"
#include "tests/support/temp_dir.h"

namespace proctex::catalog {
namespace {

namespace fs = std::filesystem;
using proctex::testing::TempDir;

BuildOptions tiny_build(const fs::path& db, const std::vector<std::string>& shaders, const std::string& shard = "1/1") {
  BuildOptions o;
  o.db = db;
  o.shaders = shaders;
  o.settings.samples = 6;
  o.settings.resolution = 64;
  o.settings.screen_resolution = 64;
  o.settings.thumbnail = 32;
  o.settings.probes = 2;
  o.settings.max_iterations = 1;
  o.seed = 5;
  o.jobs = 2;
  o.shard = Shard::parse(shard);
  return o;
}

std::string merge_error(const fs::path& out, const std::vector<fs::path>& inputs) {
  try {
    merge(out, inputs);
  } catch (const Error& e) {
    return e.message();
  }
  return "(no error)";
}

const std::vector<std::string> kShaders = {"checker", "circle", "stripes"};

TEST(CatalogShardPlan, DefaultLibraryWithin20PercentOfTheMeanForUpTo16Shards) {
  const auto names = ShaderLibrary::builtin().names();
  const ShaderCosts costs = resolve_costs(names, {});
  double total = 0;
  for (const auto& n : names) {
    EXPECT_EQ(costs.origin.at(n), "table") << n << ": every library shader has a measured cost in the table";
    total += costs.cost.at(n);
  }
  for (int n : {2, 3, 4, 8, 16}) {
    const ShardPlan p = plan_shards(names, n, costs);
    ASSERT_EQ(static_cast<int>(p.shards.size()), n);
    // Every shader exactly once.
    std::vector<std::string> all;
    for (const auto& s : p.shards) all.insert(all.end(), s.begin(), s.end());
    std::sort(all.begin(), all.end());
    auto sorted = names;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(all, sorted) << n;
    // Loads recomputed here from the costs, not taken from the plan.
    double slowest = 0;
    for (const auto& s : p.shards) {
      double load = 0;
      for (const auto& name : s) load += costs.cost.at(name);
      slowest = std::max(slowest, load);
    }
    EXPECT_LE(slowest, 1.2 * total / n) << "n = " << n << ": slowest shard " << slowest << " of total " << total;
    EXPECT_NEAR(p.balance(), slowest / (total / n), 1e-9);
  }
}

TEST(CatalogShardPlan, DeterministicWhateverTheInputOrder) {
  auto names = ShaderLibrary::builtin().names();
  const ShardPlan a = plan_shards(names, 8, resolve_costs(names, {}));
  std::mt19937 rng(3);
  for (int k = 0; k < 5; ++k) {
    std::shuffle(names.begin(), names.end(), rng);
    const ShardPlan b = plan_shards(names, 8, resolve_costs(names, {}));
    EXPECT_EQ(a.shards, b.shards);
    EXPECT_EQ(a.hash(), b.hash());
  }
  // More shards than shaders: the extra shards are empty, nothing is lost.
  const ShardPlan wide = plan_shards({"b", "a"}, 4, resolve_costs({"b", "a"}, {}));
  EXPECT_EQ(wide.shards[0], std::vector<std::string>{"a"});
  EXPECT_EQ(wide.shards[1], std::vector<std::string>{"b"});
  EXPECT_TRUE(wide.shards[2].empty());
}

TEST(CatalogShardPlan, MeasuredCostsWinAndTheTableIsScaledToThem) {
  // Measured in another unit (CPU seconds, here twice the table): bricks measured, clouds from the
  // table scaled by the median ratio 2, an unknown shader gets the median of the known costs.
  const auto c = resolve_costs({"bricks", "clouds", "zzz"}, {{"bricks", 17.6}, {"marble", 22.2}});
  EXPECT_EQ(c.origin.at("bricks"), "measured");
  EXPECT_DOUBLE_EQ(c.cost.at("bricks"), 17.6);
  EXPECT_EQ(c.origin.at("clouds"), "table");
  EXPECT_NEAR(c.cost.at("clouds"), 2 * builtin_costs().at("clouds"), 1e-9);
  EXPECT_EQ(c.origin.at("zzz"), "estimate");
  EXPECT_NEAR(c.cost.at("zzz"), (17.6 + 2 * builtin_costs().at("clouds")) / 2, 1e-9);
  // One heavy shader goes alone; the others share the second shard.
  const ShardPlan p = plan_shards({"a", "b", "c"}, 2, resolve_costs({"a", "b", "c"}, {{"a", 10}, {"b", 4}, {"c", 5}}));
  EXPECT_EQ(p.shards[0], std::vector<std::string>{"a"});
  EXPECT_EQ(p.shards[1], (std::vector<std::string>{"b", "c"}));
}

TEST(CatalogShardPlan, CostFilesJsonAndErrors) {
  TempDir dir;
  {
    std::ofstream(dir / "costs.json") << R"({"bricks": 3.5, "clouds": 1})";
    std::ofstream(dir / "bad.json") << R"({"bricks": "slow"})";
    std::ofstream(dir / "junk.json") << "not json";
  }
  const auto m = read_costs(dir / "costs.json");
  EXPECT_DOUBLE_EQ(m.at("bricks"), 3.5);
  EXPECT_DOUBLE_EQ(m.at("clouds"), 1.0);
  EXPECT_THROW(read_costs(dir / "bad.json"), Error);
  EXPECT_THROW(read_costs(dir / "junk.json"), Error);
  EXPECT_THROW(read_costs(dir / "missing.json"), Error);
}

// Builds the three shards of kShaders once; the tests copy what they tamper with.
class CatalogShardMerge : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    for (int i = 1; i <= 3; ++i) build(tiny_build(shard(i), kShaders, std::to_string(i) + "/3"));
    build(tiny_build(*dir_ / "full.sqlite", kShaders));
  }
  static void TearDownTestSuite() { delete dir_; }
  static fs::path shard(int i) { return *dir_ / ("shard-" + std::to_string(i) + ".sqlite"); }
  static fs::path copy(const fs::path& from, const std::string& name) {
    const fs::path to = *dir_ / name;
    fs::copy_file(from, to, fs::copy_options::overwrite_existing);
    return to;
  }
  static TempDir* dir_;
};
TempDir* CatalogShardMerge::dir_ = nullptr;

TEST_F(CatalogShardMerge, RecordsMeasuredCostsAndMergesToTheFullBuild) {
  Store full(*dir_ / "full.sqlite", Store::Access::Read);
  EXPECT_EQ(full.schema_version(), 3);
  for (const auto& s : full.shaders()) EXPECT_GT(s.cpu_seconds, 0.0) << s.name << ": CPU cost recorded";
  const auto costs = read_costs(*dir_ / "full.sqlite");
  EXPECT_EQ(costs.size(), 3u);
  // Each shard holds exactly its planned shaders.
  const ShardPlan plan = plan_shards(kShaders, 3, resolve_costs(kShaders, {}));
  for (int i = 1; i <= 3; ++i) {
    Store s(shard(i), Store::Access::Read);
    std::vector<std::string> names;
    for (const auto& sum : s.shaders()) names.push_back(sum.name);
    EXPECT_EQ(names, plan.shards[i - 1]) << i;
  }
  const fs::path out = *dir_ / "merged.sqlite";
  fs::remove(out);
  const auto r = merge(out, {shard(3), shard(1), shard(2)});
  EXPECT_EQ(r.added.size(), 3u);
  Store m(out, Store::Access::Read);
  for (const auto& s : full.shaders()) {
    const auto got = m.summary(s.name);
    ASSERT_TRUE(got) << s.name;
    EXPECT_EQ(got->content_hash, s.content_hash) << s.name;
    EXPECT_GT(got->cpu_seconds, 0.0) << s.name << ": the cost travels with the merge";
  }
}

TEST_F(CatalogShardMerge, MissingShardIsNamedWithItsShaders) {
  const fs::path out = *dir_ / "partial.sqlite";
  fs::remove(out);
  const ShardPlan plan = plan_shards(kShaders, 3, resolve_costs(kShaders, {}));
  const std::string msg = merge_error(out, {shard(1), shard(3)});
  EXPECT_NE(msg.find("shard 2/3 is missing"), std::string::npos) << msg;
  for (const auto& name : plan.shards[1]) EXPECT_NE(msg.find(name), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(out)) << "nothing written";
  MergeOptions partial;
  partial.allow_partial = true;
  EXPECT_EQ(merge(out, {shard(1), shard(3)}, partial).added.size(), plan.shards[0].size() + plan.shards[2].size());
}

TEST_F(CatalogShardMerge, DifferentSeedSettingsMetricVersionOrSourceAreRefusedNamingTheFirstDifference) {
  TempDir local;
  // Shard 2 again with another seed / sample count: disjoint shaders, so only the check sees it.
  auto seed = tiny_build(local / "seed.sqlite", kShaders, "2/3");
  seed.seed = 6;
  build(seed);
  auto samples = tiny_build(local / "samples.sqlite", kShaders, "2/3");
  samples.settings.samples = 5;
  build(samples);
  const fs::path out = local / "out.sqlite";
  std::string msg = merge_error(out, {shard(1), local / "seed.sqlite", shard(3)});
  EXPECT_NE(msg.find("seed = 6"), std::string::npos) << msg;
  EXPECT_NE(msg.find("seed.sqlite"), std::string::npos) << msg;
  msg = merge_error(out, {shard(1), local / "samples.sqlite", shard(3)});
  EXPECT_NE(msg.find("setting samples = 5"), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(out));

  // Another metric version (what a shard built by an older proctex records).
  const fs::path metric = copy(shard(2), "metric.sqlite");
  {
    sql::Connection c(metric, sql::Connection::Mode::ReadWrite);
    c.exec("UPDATE shaders SET metric_version = metric_version + 1");
  }
  msg = merge_error(out, {shard(1), metric, shard(3)});
  EXPECT_NE(msg.find("metric version"), std::string::npos) << msg;

  // Another shader source: shard 1 was built from a checkout where shard 2's shader differs. Each
  // shard records the sources of every selected shader, so disjoint shards still disagree.
  const std::string victim = plan_shards(kShaders, 3, resolve_costs(kShaders, {})).shards[1].front();
  const fs::path source = copy(shard(1), "source.sqlite");
  {
    Store s(source, Store::Access::Read);
    auto info = s.builds().back()["info"];
    info["sources"][victim] = "0123456789abcdef";
    sql::Connection c(source, sql::Connection::Mode::ReadWrite);
    auto u = c.prepare("UPDATE builds SET info = ?1 WHERE id = (SELECT max(id) FROM builds)");
    u.bind(1, info.dump());
    u.run();
  }
  msg = merge_error(out, {source, shard(2), shard(3)});
  EXPECT_NE(msg.find("different source of shader '" + victim + "'"), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(out));
  MergeOptions mixed;
  mixed.allow_mixed = true;
  EXPECT_EQ(merge(out, {source, shard(2), shard(3)}, mixed).added.size(), 3u);
}

TEST_F(CatalogShardMerge, UnfinishedShardIsRefused) {
  const fs::path killed = copy(shard(2), "killed.sqlite");
  {
    sql::Connection c(killed, sql::Connection::Mode::ReadWrite);
    c.exec("UPDATE builds SET finished_at = NULL, result = NULL WHERE id = (SELECT max(id) FROM builds)");
  }
  const std::string msg = merge_error(*dir_ / "unfinished.sqlite", {shard(1), killed, shard(3)});
  EXPECT_NE(msg.find("did not finish"), std::string::npos) << msg;
  EXPECT_NE(msg.find("killed.sqlite"), std::string::npos) << msg;
}

TEST_F(CatalogShardMerge, SchemaV2FileIsReadableAndMigratesKeepingItsContent) {
  // A v2 file is a v3 file without shader_costs.
  const fs::path v2 = copy(*dir_ / "full.sqlite", "v2.sqlite");
  {
    sql::Connection c(v2, sql::Connection::Mode::ReadWrite);
    c.exec("DROP TABLE shader_costs; PRAGMA user_version = 2");
  }
  std::map<std::string, std::string> before;
  {
    Store s(v2, Store::Access::Read);
    EXPECT_EQ(s.schema_version(), 2) << "read without migrating";
    for (const auto& sum : s.shaders()) {
      EXPECT_LT(sum.cpu_seconds, 0) << "no measured cost in a v2 file";
      before[sum.name] = sum.content_hash;
    }
    EXPECT_EQ(s.load("circle").samples.size(), 6u);
  }
  const auto costs = read_costs(v2);  // falls back to the recorded build seconds
  EXPECT_EQ(costs.size(), 3u);
  for (const auto& [k, v] : costs) EXPECT_GT(v, 0) << k;
  {
    Store s(v2, Store::Access::Write);
    EXPECT_EQ(s.schema_version(), kSchemaVersion);
    for (const auto& sum : s.shaders()) EXPECT_EQ(before.at(sum.name), sum.content_hash);
    for (const auto& sum : s.shaders()) EXPECT_TRUE(s.consistency_problems(sum.name).empty()) << sum.name;
    EXPECT_TRUE(s.integrity_problems().empty());
  }
}

}  // namespace
}  // namespace proctex::catalog
