#include "catalog/store.h"

#include <chrono>
#include <ctime>
#include <functional>

#include "catalog/sqlite.h"
#include "core/error.h"
#include "core/version.h"

namespace proctex::catalog {
namespace fs = std::filesystem;

namespace {

// Forward migrations: kMigrations[v - 1] takes a file from user_version v - 1 to v. Never edit a
// released step; add a new one and bump kSchemaVersion.
const char* const kMigrations[] = {
    // 0 -> 1: the first schema.
    R"sql(
CREATE TABLE shaders (
  id              INTEGER PRIMARY KEY,
  name            TEXT NOT NULL UNIQUE,
  family          TEXT NOT NULL,
  source_hash     TEXT NOT NULL,   -- ShaderDecl::source_hash when built (staleness)
  settings_hash   TEXT NOT NULL,   -- SamplingSettings::hash(seed): incremental rebuilds
  content_hash    TEXT NOT NULL,   -- vectors, seeds, features, pruned graph: merge conflicts
  declaration     TEXT NOT NULL,   -- JSON: the parameter declaration as data
  mode            TEXT NOT NULL,   -- adaptive | uniform
  metric          TEXT NOT NULL,
  metric_version  INTEGER NOT NULL,
  resolution      INTEGER NOT NULL,
  seed            TEXT NOT NULL,   -- build seed (uint64 as decimal text)
  settings        TEXT NOT NULL,   -- JSON SamplingSettings
  stats           TEXT NOT NULL,   -- JSON: kappa per iteration, candidate counts, timings
  coverage        TEXT,            -- JSON probe coverage, NULL when not measured
  sample_count    INTEGER NOT NULL,
  pruned_count    INTEGER NOT NULL,
  device          TEXT NOT NULL,
  proctex_version TEXT NOT NULL,
  build_seconds   REAL NOT NULL,
  built_at        TEXT NOT NULL
);
CREATE TABLE samples (
  shader_id  INTEGER NOT NULL REFERENCES shaders(id) ON DELETE CASCADE,
  idx        INTEGER NOT NULL,
  unit       BLOB NOT NULL,        -- float32 LE, normalised (unit cube) parameter vector
  packed     BLOB NOT NULL,        -- float32 LE, packed vector the shader received
  seed       INTEGER NOT NULL,
  smoothness REAL,                 -- H (thesis eq 4.2), NULL in uniform mode
  thumbnail  BLOB NOT NULL,        -- PNG, 8-bit sRGB
  PRIMARY KEY (shader_id, idx)
) WITHOUT ROWID;
CREATE TABLE features (
  shader_id  INTEGER NOT NULL,
  idx        INTEGER NOT NULL,
  metric     TEXT NOT NULL,
  version    INTEGER NOT NULL,
  resolution INTEGER NOT NULL,
  vector     BLOB NOT NULL,        -- float32 LE
  PRIMARY KEY (shader_id, idx, metric, resolution),
  FOREIGN KEY (shader_id, idx) REFERENCES samples(shader_id, idx) ON DELETE CASCADE
) WITHOUT ROWID;
CREATE TABLE edges (
  shader_id INTEGER NOT NULL,
  a         INTEGER NOT NULL,
  b         INTEGER NOT NULL,
  metric    TEXT NOT NULL,
  weight    REAL NOT NULL,         -- similarity of samples a and b (a < b): fully connected
  PRIMARY KEY (shader_id, a, b, metric),
  CHECK (a < b),
  FOREIGN KEY (shader_id, a) REFERENCES samples(shader_id, idx) ON DELETE CASCADE,
  FOREIGN KEY (shader_id, b) REFERENCES samples(shader_id, idx) ON DELETE CASCADE
) WITHOUT ROWID;
CREATE INDEX edges_b ON edges(shader_id, b);
CREATE TABLE graph_members (
  shader_id INTEGER NOT NULL,
  idx       INTEGER NOT NULL,
  graph     TEXT NOT NULL CHECK (graph IN ('full', 'pruned')),
  PRIMARY KEY (shader_id, idx, graph),
  FOREIGN KEY (shader_id, idx) REFERENCES samples(shader_id, idx) ON DELETE CASCADE
) WITHOUT ROWID;
CREATE TABLE builds (
  id          INTEGER PRIMARY KEY,
  command     TEXT NOT NULL,
  started_at  TEXT NOT NULL,
  finished_at TEXT,
  info        TEXT NOT NULL,       -- JSON: seed, settings, shard, shaders, proctex version, device
  result      TEXT                 -- JSON: per shader status and seconds
);
)sql",
    // 1 -> 2: jump edges between shaders (proctex catalog link, thesis 5.3). A shader's rows
    // cascade: rebuilding it (delete + insert) drops jump edges found from its old samples.
    R"sql(
CREATE TABLE jumps (
  id          INTEGER PRIMARY KEY,
  shader_a    INTEGER NOT NULL REFERENCES shaders(id) ON DELETE CASCADE,
  shader_b    INTEGER NOT NULL REFERENCES shaders(id) ON DELETE CASCADE,
  packed_a    BLOB NOT NULL,        -- float32 LE, packed vector of shader a
  packed_b    BLOB NOT NULL,
  seed_a      INTEGER NOT NULL,
  seed_b      INTEGER NOT NULL,
  metric      TEXT NOT NULL,
  version     INTEGER NOT NULL,
  resolution  INTEGER NOT NULL,
  features_a  BLOB NOT NULL,        -- float32 LE, features of the render of packed_a
  features_b  BLOB NOT NULL,
  weight      REAL NOT NULL,        -- similarity of the two renders
  info        TEXT NOT NULL,        -- JSON: start pair, rounds, renders
  created_at  TEXT NOT NULL,
  CHECK (shader_a <> shader_b)
);
CREATE INDEX jumps_a ON jumps(shader_a);
CREATE INDEX jumps_b ON jumps(shader_b);
)sql",
    // 2 -> 3: the measured build cost per shader, which balances `catalog build --shard i/n`
    // (catalog/shard.h). Its own table, so v1/v2 readers' queries are untouched; IF NOT EXISTS so a
    // file whose user_version was lowered by hand migrates again without an error.
    R"sql(
CREATE TABLE IF NOT EXISTS shader_costs (
  shader_id    INTEGER PRIMARY KEY REFERENCES shaders(id) ON DELETE CASCADE,
  cpu_seconds  REAL NOT NULL,       -- process CPU time of the build (all threads): load-independent
  wall_seconds REAL NOT NULL        -- the same as shaders.build_seconds
);
)sql",
};
static_assert(std::size(kMigrations) == kSchemaVersion);

std::string now_utc() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

nlohmann::json parse_json(const std::string& text) {
  if (text.empty()) return nullptr;
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception&) {
    throw Error("catalogue holds malformed JSON metadata", "the file is damaged; rebuild it");
  }
}

}  // namespace

Store::Store(const fs::path& path, Access access) : path_(path) {
  std::error_code ec;
  if (fs::is_directory(path, ec))
    throw Error("catalogue path '" + path.string() + "' is a folder", "pass a file name, e.g. --db " + (path / "catalog.sqlite").string());
  const bool exists = fs::exists(path, ec);
  if (access == Access::Read) {
    if (!exists)
      throw Error("no catalogue at '" + path.string() + "'", "build one with 'proctex catalog build --db " + path.string() + "'");
    db_ = std::make_unique<sql::Connection>(path, sql::Connection::Mode::ReadOnly);
  } else {
    if (!exists && path.has_parent_path()) {
      fs::create_directories(path.parent_path(), ec);
      if (ec || !fs::is_directory(path.parent_path()))
        throw Error("cannot create the folder for catalogue '" + path.string() + "': " + ec.message(),
                    "pass a --db path in a writable folder");
    }
    db_ = std::make_unique<sql::Connection>(path, exists ? sql::Connection::Mode::ReadWrite : sql::Connection::Mode::Create);
  }
  check_and_migrate(access == Access::Write);
}

Store::~Store() = default;

int Store::schema_version() const { return static_cast<int>(db_->scalar_int("PRAGMA user_version")); }

void Store::check_and_migrate(bool writable) {
  // Nothing below writes until every check has passed: a refused file is left as it was.
  const int64_t version = db_->scalar_int("PRAGMA user_version");  // reading the header: NOTADB here
  const int64_t app = db_->scalar_int("PRAGMA application_id");
  const int64_t objects = db_->scalar_int("SELECT count(*) FROM sqlite_schema");
  if (objects > 0 && app != kApplicationId)
    throw Error("'" + path_.string() + "' is a SQLite database but not a proctex catalogue",
                "pass another --db; proctex does not write into foreign databases");
  if (version > kSchemaVersion)
    throw Error("catalogue '" + path_.string() + "' has schema version " + std::to_string(version) +
                    ", newer than this proctex supports (" + std::to_string(kSchemaVersion) + ")",
                "use the proctex release that wrote it, or build a new catalogue with another --db; the file was not changed");
  if (!writable) {
    if (version < kMinReadableVersion)
      throw Error("catalogue '" + path_.string() + "' has the older schema version " + std::to_string(version),
                  "run 'proctex catalog build --db " + path_.string() + "' once to migrate it");
    db_->exec("PRAGMA foreign_keys = ON");
    return;
  }
  if (objects > 0) {
    const std::string check = db_->scalar_text("PRAGMA quick_check");
    if (check != "ok")
      throw Error("catalogue '" + path_.string() + "' is corrupt (" + check + ")",
                  "keep it for diagnosis and build into a new file; the file was not changed");
  }
  db_->exec("PRAGMA journal_mode = WAL");
  db_->exec("PRAGMA synchronous = NORMAL");
  db_->exec("PRAGMA foreign_keys = ON");
  if (version < kSchemaVersion) {
    sql::Transaction t(*db_);
    for (int64_t v = version; v < kSchemaVersion; ++v) db_->exec(kMigrations[v]);
    // PRAGMAs take no bound parameters; both values are compile-time integers.
    db_->exec("PRAGMA application_id = " + std::to_string(kApplicationId));
    db_->exec("PRAGMA user_version = " + std::to_string(kSchemaVersion));
    t.commit();
  }
}

namespace {

const char* kSummaryColumns =
    "name, family, source_hash, settings_hash, content_hash, mode, metric, metric_version, resolution, seed, "
    "settings, stats, coverage, sample_count, pruned_count, device, proctex_version, build_seconds, built_at";

// The summary columns plus the measured CPU cost (schema v3; NULL for older files read as they are).
std::string summary_select(int version) {
  return std::string("SELECT ") + kSummaryColumns +
         (version >= 3 ? ", (SELECT cpu_seconds FROM shader_costs c WHERE c.shader_id = shaders.id)" : ", NULL") +
         " FROM shaders";
}

ShaderSummary read_summary(sql::Statement& s) {
  ShaderSummary r;
  r.name = s.column_text(0);
  r.family = s.column_text(1);
  r.source_hash = s.column_text(2);
  r.settings_hash = s.column_text(3);
  r.content_hash = s.column_text(4);
  r.mode = s.column_text(5);
  r.metric = s.column_text(6);
  r.metric_version = static_cast<int>(s.column_int(7));
  r.resolution = static_cast<int>(s.column_int(8));
  r.seed = std::stoull(s.column_text(9).empty() ? "0" : s.column_text(9));
  r.settings = parse_json(s.column_text(10));
  r.stats = parse_json(s.column_text(11));
  if (!s.is_null(12)) {
    const auto j = parse_json(s.column_text(12));
    Coverage c;
    c.probes = j.value("probes", 0);
    c.mean = j.value("mean", 0.0);
    c.median = j.value("median", 0.0);
    c.p10 = j.value("p10", 0.0);
    c.min = j.value("min", 0.0);
    c.max = j.value("max", 0.0);
    r.coverage = c;
  }
  r.samples = static_cast<int>(s.column_int(13));
  r.pruned = static_cast<int>(s.column_int(14));
  r.device = s.column_text(15);
  r.proctex_version = s.column_text(16);
  r.build_seconds = s.column_double(17);
  r.built_at = s.column_text(18);
  r.cpu_seconds = s.is_null(19) ? -1.0 : s.column_double(19);
  return r;
}

}  // namespace

std::vector<ShaderSummary> Store::shaders() {
  std::vector<ShaderSummary> out;
  auto s = db_->prepare(summary_select(schema_version()) + " ORDER BY name");
  while (s.step()) out.push_back(read_summary(s));
  return out;
}

std::optional<ShaderSummary> Store::summary(const std::string& shader) {
  auto s = db_->prepare(summary_select(schema_version()) + " WHERE name = ?1");
  s.bind(1, shader);
  if (!s.step()) return std::nullopt;
  return read_summary(s);
}

ShaderCatalogue Store::load(const std::string& shader, bool with_edges) {
  auto id_stmt = db_->prepare("SELECT id, declaration FROM shaders WHERE name = ?1");
  id_stmt.bind(1, shader);
  if (!id_stmt.step())
    throw UsageError("shader '" + shader + "' is not in catalogue '" + path_.string() + "'",
                     "see 'proctex catalog info --db " + path_.string() + "', or build it with --shaders " + shader);
  const int64_t id = id_stmt.column_int(0);
  const auto sum = summary(shader).value();
  ShaderCatalogue cat;
  cat.shader = sum.name;
  cat.family = sum.family;
  cat.source_hash = sum.source_hash;
  cat.settings_hash = sum.settings_hash;
  cat.content_hash = sum.content_hash;
  cat.declaration = parse_json(id_stmt.column_text(1));
  cat.settings = SamplingSettings::from_json(sum.settings);
  cat.seed = sum.seed;
  cat.stats = sum.stats;
  if (sum.coverage) cat.coverage = *sum.coverage;

  auto s = db_->prepare("SELECT idx, unit, packed, seed, smoothness, thumbnail FROM samples WHERE shader_id = ?1 ORDER BY idx");
  s.bind(1, id);
  while (s.step()) {
    if (s.column_int(0) != static_cast<int64_t>(cat.samples.size()))
      throw Error("catalogue shader '" + shader + "' has a gap in its sample indices", "rebuild the shader");
    Sample smp;
    smp.unit = sql::blob_to_floats(s.column_blob(1));
    smp.packed = sql::blob_to_floats(s.column_blob(2));
    smp.seed = static_cast<uint32_t>(s.column_int(3));
    smp.smoothness = s.is_null(4) ? -1.0 : s.column_double(4);
    smp.thumbnail = s.column_blob(5);
    cat.samples.push_back(std::move(smp));
  }
  const int n = static_cast<int>(cat.samples.size());
  auto f = db_->prepare("SELECT idx, metric, version, resolution, vector FROM features WHERE shader_id = ?1 AND metric = ?2");
  f.bind(1, id).bind(2, sum.metric);
  while (f.step()) {
    const int64_t idx = f.column_int(0);
    if (idx < 0 || idx >= n) continue;
    cat.samples[idx].features = {f.column_text(1), static_cast<int>(f.column_int(2)), static_cast<int>(f.column_int(3)),
                                 sql::blob_to_floats(f.column_blob(4))};
  }
  if (with_edges) {
    cat.edges.assign(size_t(n) * n, 1.0);
    auto e = db_->prepare("SELECT a, b, weight FROM edges WHERE shader_id = ?1 AND metric = ?2");
    e.bind(1, id).bind(2, sum.metric);
    while (e.step()) {
      const int64_t a = e.column_int(0), b = e.column_int(1);
      if (a < 0 || b < 0 || a >= n || b >= n) continue;
      cat.edges[a * n + b] = cat.edges[b * n + a] = e.column_double(2);
    }
  }
  auto g = db_->prepare("SELECT idx FROM graph_members WHERE shader_id = ?1 AND graph = 'pruned' ORDER BY idx");
  g.bind(1, id);
  while (g.step()) cat.pruned.push_back(static_cast<int>(g.column_int(0)));
  return cat;
}

void Store::write(const ShaderCatalogue& cat, const std::string& device, double seconds, double cpu_seconds) {
  sql::Transaction t(*db_);
  remove(cat.shader);
  const auto& m = cat.samples.empty() ? metrics::Features{} : cat.samples.front().features;
  auto ins = db_->prepare(
      "INSERT INTO shaders (name, family, source_hash, settings_hash, content_hash, declaration, mode, metric, "
      "metric_version, resolution, seed, settings, stats, coverage, sample_count, pruned_count, device, "
      "proctex_version, build_seconds, built_at) "
      "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18, ?19, ?20)");
  ins.bind(1, cat.shader).bind(2, cat.family).bind(3, cat.source_hash).bind(4, cat.settings_hash)
      .bind(5, cat.content_hash).bind(6, cat.declaration.dump()).bind(7, cat.settings.mode)
      .bind(8, m.metric.empty() ? cat.settings.metric : m.metric).bind(9, m.version)
      .bind(10, cat.settings.resolution).bind(11, std::to_string(cat.seed)).bind(12, cat.settings.to_json().dump())
      .bind(13, cat.stats.dump());
  if (cat.coverage.probes > 0) ins.bind(14, cat.coverage.to_json().dump());
  else ins.bind_null(14);
  ins.bind(15, static_cast<int64_t>(cat.samples.size())).bind(16, static_cast<int64_t>(cat.pruned.size()))
      .bind(17, device).bind(18, kVersion).bind(19, seconds).bind(20, now_utc());
  ins.run();
  const int64_t id = db_->scalar_int("SELECT last_insert_rowid()");
  if (cpu_seconds >= 0) {
    auto cost = db_->prepare("INSERT INTO shader_costs (shader_id, cpu_seconds, wall_seconds) VALUES (?1, ?2, ?3)");
    cost.bind(1, id).bind(2, cpu_seconds).bind(3, seconds);
    cost.run();
  }

  auto smp = db_->prepare("INSERT INTO samples (shader_id, idx, unit, packed, seed, smoothness, thumbnail) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)");
  auto feat = db_->prepare("INSERT INTO features (shader_id, idx, metric, version, resolution, vector) VALUES (?1, ?2, ?3, ?4, ?5, ?6)");
  auto mem = db_->prepare("INSERT INTO graph_members (shader_id, idx, graph) VALUES (?1, ?2, ?3)");
  const int n = static_cast<int>(cat.samples.size());
  for (int i = 0; i < n; ++i) {
    const Sample& s = cat.samples[i];
    smp.bind(1, id).bind(2, i).bind_blob(3, sql::floats_to_blob(s.unit)).bind_blob(4, sql::floats_to_blob(s.packed))
        .bind(5, static_cast<int64_t>(s.seed));
    if (s.smoothness >= 0) smp.bind(6, s.smoothness);
    else smp.bind_null(6);
    smp.bind_blob(7, s.thumbnail);
    smp.run();
    feat.bind(1, id).bind(2, i).bind(3, s.features.metric).bind(4, s.features.version).bind(5, s.features.resolution)
        .bind_blob(6, sql::floats_to_blob(s.features.values));
    feat.run();
    mem.bind(1, id).bind(2, i).bind(3, "full");
    mem.run();
  }
  for (int i : cat.pruned) {
    mem.bind(1, id).bind(2, i).bind(3, "pruned");
    mem.run();
  }
  auto edge = db_->prepare("INSERT INTO edges (shader_id, a, b, metric, weight) VALUES (?1, ?2, ?3, ?4, ?5)");
  const std::string metric = m.metric.empty() ? cat.settings.metric : m.metric;
  if (cat.edges.size() == size_t(n) * n)
    for (int a = 0; a < n; ++a)
      for (int b = a + 1; b < n; ++b) {
        edge.bind(1, id).bind(2, a).bind(3, b).bind(4, metric).bind(5, cat.edge(a, b));
        edge.run();
      }
  t.commit();
}

void Store::remove(const std::string& shader) {
  auto q = db_->prepare("SELECT id FROM shaders WHERE name = ?1");
  q.bind(1, shader);
  if (!q.step()) return;
  const int64_t id = q.column_int(0);
  // Children first, explicitly: cheaper than cascading row by row.
  auto j = db_->prepare("DELETE FROM jumps WHERE shader_a = ?1 OR shader_b = ?1");
  j.bind(1, id);
  j.run();
  if (schema_version() >= 3) {
    auto c = db_->prepare("DELETE FROM shader_costs WHERE shader_id = ?1");
    c.bind(1, id);
    c.run();
  }
  for (const char* table : {"edges", "graph_members", "features", "samples", "shaders"}) {
    auto d = db_->prepare(std::string("DELETE FROM ") + table + (std::string(table) == "shaders" ? " WHERE id = ?1" : " WHERE shader_id = ?1"));
    d.bind(1, id);
    d.run();
  }
}

namespace {

int64_t shader_id(sql::Connection& db, const std::string& shader, const std::filesystem::path& path) {
  auto q = db.prepare("SELECT id FROM shaders WHERE name = ?1");
  q.bind(1, shader);
  if (!q.step())
    throw UsageError("shader '" + shader + "' is not in catalogue '" + path.string() + "'",
                     "build it first: proctex catalog build --db " + path.string() + " --shaders " + shader);
  return q.column_int(0);
}

}  // namespace

void Store::write_jumps(const std::string& a, const std::string& b, const std::vector<JumpEdge>& jumps) {
  if (a == b) throw UsageError("a jump edge joins two different shaders, got '" + a + "' twice");
  const std::string lo = std::min(a, b), hi = std::max(a, b);
  const int64_t ida = shader_id(*db_, lo, path_), idb = shader_id(*db_, hi, path_);
  sql::Transaction t(*db_);
  auto del = db_->prepare("DELETE FROM jumps WHERE shader_a = ?1 AND shader_b = ?2");
  del.bind(1, ida).bind(2, idb);
  del.run();
  auto ins = db_->prepare(
      "INSERT INTO jumps (shader_a, shader_b, packed_a, packed_b, seed_a, seed_b, metric, version, resolution, "
      "features_a, features_b, weight, info, created_at) "
      "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14)");
  for (JumpEdge e : jumps) {
    if (e.shader_a != lo) {  // store in name order
      std::swap(e.shader_a, e.shader_b);
      std::swap(e.packed_a, e.packed_b);
      std::swap(e.seed_a, e.seed_b);
      std::swap(e.features_a, e.features_b);
    }
    if (e.shader_a != lo || e.shader_b != hi)
      throw Error("jump edge " + e.shader_a + " - " + e.shader_b + " written as " + lo + " - " + hi + " (bug)");
    if (e.features_a.metric != e.features_b.metric || e.features_a.version != e.features_b.version ||
        e.features_a.resolution != e.features_b.resolution)
      throw Error("jump edge features of " + lo + " and " + hi + " come from different metrics (bug)");
    ins.bind(1, ida).bind(2, idb).bind_blob(3, sql::floats_to_blob(e.packed_a)).bind_blob(4, sql::floats_to_blob(e.packed_b))
        .bind(5, static_cast<int64_t>(e.seed_a)).bind(6, static_cast<int64_t>(e.seed_b)).bind(7, e.features_a.metric)
        .bind(8, e.features_a.version).bind(9, e.features_a.resolution)
        .bind_blob(10, sql::floats_to_blob(e.features_a.values)).bind_blob(11, sql::floats_to_blob(e.features_b.values))
        .bind(12, e.similarity).bind(13, e.info.dump()).bind(14, now_utc());
    ins.run();
  }
  t.commit();
}

std::vector<JumpEdge> Store::jumps(const std::string& shader) {
  std::vector<JumpEdge> out;
  if (schema_version() < 2) return out;  // a v1 file read without migrating: no jump edges yet
  auto s = db_->prepare(
      "SELECT sa.name, sb.name, j.packed_a, j.packed_b, j.seed_a, j.seed_b, j.metric, j.version, j.resolution, "
      "j.features_a, j.features_b, j.weight, j.info FROM jumps j JOIN shaders sa ON sa.id = j.shader_a "
      "JOIN shaders sb ON sb.id = j.shader_b WHERE ?1 = '' OR sa.name = ?1 OR sb.name = ?1 ORDER BY sa.name, sb.name, j.id");
  s.bind(1, shader);
  while (s.step()) {
    JumpEdge e;
    e.shader_a = s.column_text(0);
    e.shader_b = s.column_text(1);
    e.packed_a = sql::blob_to_floats(s.column_blob(2));
    e.packed_b = sql::blob_to_floats(s.column_blob(3));
    e.seed_a = static_cast<uint32_t>(s.column_int(4));
    e.seed_b = static_cast<uint32_t>(s.column_int(5));
    const std::string metric = s.column_text(6);
    const int version = static_cast<int>(s.column_int(7)), resolution = static_cast<int>(s.column_int(8));
    e.features_a = {metric, version, resolution, sql::blob_to_floats(s.column_blob(9))};
    e.features_b = {metric, version, resolution, sql::blob_to_floats(s.column_blob(10))};
    e.similarity = s.column_double(11);
    e.info = parse_json(s.column_text(12));
    out.push_back(std::move(e));
  }
  return out;
}

int64_t Store::begin_build(const nlohmann::json& info) {
  auto s = db_->prepare("INSERT INTO builds (command, started_at, info) VALUES (?1, ?2, ?3)");
  s.bind(1, info.value("command", std::string("build"))).bind(2, now_utc()).bind(3, info.dump());
  s.run();
  return db_->scalar_int("SELECT last_insert_rowid()");
}

void Store::finish_build(int64_t id, const nlohmann::json& result) {
  auto s = db_->prepare("UPDATE builds SET finished_at = ?1, result = ?2 WHERE id = ?3");
  s.bind(1, now_utc()).bind(2, result.dump()).bind(3, id);
  s.run();
}

nlohmann::json Store::builds() {
  nlohmann::json out = nlohmann::json::array();
  auto s = db_->prepare("SELECT id, command, started_at, finished_at, info, result FROM builds ORDER BY id");
  while (s.step())
    out.push_back({{"id", s.column_int(0)}, {"command", s.column_text(1)}, {"started_at", s.column_text(2)},
                   {"finished_at", s.is_null(3) ? nlohmann::json() : nlohmann::json(s.column_text(3))},
                   {"info", parse_json(s.column_text(4))}, {"result", parse_json(s.column_text(5))}});
  return out;
}

std::vector<std::string> Store::integrity_problems() {
  std::vector<std::string> out;
  auto s = db_->prepare("PRAGMA integrity_check");
  while (s.step())
    if (s.column_text(0) != "ok") out.push_back("integrity: " + s.column_text(0));
  auto fk = db_->prepare("PRAGMA foreign_key_check");
  while (fk.step()) out.push_back("foreign key: table " + fk.column_text(0) + " row " + fk.column_text(1) + " -> " + fk.column_text(2));
  if (schema_version() != kSchemaVersion) out.push_back("schema version " + std::to_string(schema_version()));
  return out;
}

std::vector<std::string> Store::consistency_problems(const std::string& shader) {
  std::vector<std::string> out;
  const ShaderCatalogue cat = load(shader);
  const auto sum = summary(shader).value();
  const int n = static_cast<int>(cat.samples.size());
  auto say = [&](const std::string& what) { out.push_back(shader + ": " + what); };
  if (n != sum.samples) say("sample_count " + std::to_string(sum.samples) + " but " + std::to_string(n) + " samples");
  if (n == 0) say("no samples");
  auto count = [&](const std::string& sqltext) {
    auto q = db_->prepare(sqltext);
    q.bind(1, shader);
    return q.step() ? q.column_int(0) : 0;
  };
  const int64_t edges = count("SELECT count(*) FROM edges e JOIN shaders s ON s.id = e.shader_id WHERE s.name = ?1");
  if (edges != int64_t(n) * (n - 1) / 2) say(std::to_string(edges) + " edges, a full graph of " + std::to_string(n) + " needs " + std::to_string(int64_t(n) * (n - 1) / 2));
  const int64_t full = count("SELECT count(*) FROM graph_members g JOIN shaders s ON s.id = g.shader_id WHERE s.name = ?1 AND g.graph = 'full'");
  if (full != n) say("full graph has " + std::to_string(full) + " of " + std::to_string(n) + " samples");
  if (static_cast<int>(cat.pruned.size()) != sum.pruned || (n > 0 && cat.pruned.empty())) say("pruned graph size mismatch");
  for (const auto& s : cat.samples) {
    if (s.features.values.empty()) { say("a sample has no features"); break; }
    if (s.features.values.size() != cat.samples.front().features.values.size()) { say("feature lengths differ"); break; }
    if (s.thumbnail.empty()) { say("a sample has no thumbnail"); break; }
  }
  ShaderCatalogue copy = cat;
  copy.finalise_hash();
  if (copy.content_hash != sum.content_hash) say("content hash mismatch (rows changed after the build)");
  return out;
}

}  // namespace proctex::catalog
