#include "server/job_store.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <random>
#include <regex>

#include <fmt/format.h>

#include "catalog/sqlite.h"
#include "core/error.h"

namespace proctex::server {
namespace fs = std::filesystem;
using catalog::sql::Connection;

namespace {

constexpr int kSchemaVersion = 1;

std::string random_id() {
  static std::mutex m;
  static std::random_device rd;
  std::lock_guard lock(m);
  std::string id;
  for (int i = 0; i < 4; ++i) id += fmt::format("{:08x}", rd());
  return id;
}

nlohmann::json parse_or_null(const std::string& text) {
  if (text.empty()) return nullptr;
  return nlohmann::json::parse(text, nullptr, false);
}

const char* kColumns = "id, kind, state, params, result, progress, error, created, started, finished";

JobRecord read_row(catalog::sql::Statement& st) {
  JobRecord r;
  r.id = st.column_text(0);
  r.kind = st.column_text(1);
  r.state = st.column_text(2);
  r.params = parse_or_null(st.column_text(3));
  r.result = st.is_null(4) ? nlohmann::json() : parse_or_null(st.column_text(4));
  r.progress = parse_or_null(st.column_text(5));
  if (r.progress.is_null()) r.progress = nlohmann::json::object();
  r.error = st.column_text(6);
  r.created = st.column_double(7);
  r.started = st.column_double(8);
  r.finished = st.column_double(9);
  return r;
}

}  // namespace

double unix_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

nlohmann::json JobRecord::to_json() const {
  nlohmann::json j = {{"id", id},           {"kind", kind},         {"state", state},
                      {"params", params},   {"progress", progress}, {"created", created},
                      {"started", started}, {"finished", finished}, {"has_result", !result.is_null()}};
  if (!error.empty()) j["error"] = error;
  return j;
}

bool JobStore::valid_id(const std::string& id) {
  static const std::regex kId("[0-9a-f]{32}");
  return std::regex_match(id, kId);
}

JobStore::JobStore(const fs::path& data_dir) : data_(data_dir) {
  std::error_code ec;
  fs::create_directories(data_ / "jobs", ec);
  fs::create_directories(data_ / "tmp", ec);
  if (!fs::is_directory(data_ / "jobs"))
    throw Error("cannot create the data folder '" + data_.string() + "'", "pass a writable --data folder");
  // Temporary uploads of an earlier process are never needed again.
  for (const auto& e : fs::directory_iterator(data_ / "tmp", ec)) fs::remove_all(e.path(), ec);
  db_ = std::make_unique<Connection>(data_ / "jobs.sqlite", Connection::Mode::Create);
  db_->exec("PRAGMA journal_mode=WAL");
  db_->exec("PRAGMA synchronous=NORMAL");
  const int64_t version = db_->scalar_int("PRAGMA user_version");
  if (version > kSchemaVersion)
    throw Error(fmt::format("job store '{}' has schema version {}, newer than this proctex ({})",
                            (data_ / "jobs.sqlite").string(), version, kSchemaVersion),
                "use a newer proctex or another --data folder");
  db_->exec(
      "CREATE TABLE IF NOT EXISTS jobs (id TEXT PRIMARY KEY, kind TEXT NOT NULL, state TEXT NOT NULL, "
      "params TEXT NOT NULL, result TEXT, progress TEXT NOT NULL DEFAULT '{}', error TEXT NOT NULL DEFAULT '', "
      "created REAL NOT NULL, started REAL NOT NULL DEFAULT 0, finished REAL NOT NULL DEFAULT 0)");
  db_->exec("CREATE INDEX IF NOT EXISTS jobs_created ON jobs(created)");
  db_->exec("PRAGMA user_version=" + std::to_string(kSchemaVersion));
  interrupted_ = static_cast<int>(db_->scalar_int("SELECT count(*) FROM jobs WHERE state IN ('queued','running')"));
  db_->exec("UPDATE jobs SET state='interrupted' WHERE state IN ('queued','running')");
}

JobStore::~JobStore() = default;

JobRecord JobStore::create(const std::string& kind, const nlohmann::json& params) {
  JobRecord r;
  r.id = random_id();
  r.kind = kind;
  r.state = "queued";
  r.params = params;
  r.created = unix_now();
  std::lock_guard lock(mutex_);
  db_->prepare("INSERT INTO jobs (id, kind, state, params, created) VALUES (?, ?, ?, ?, ?)")
      .bind(1, r.id).bind(2, r.kind).bind(3, r.state).bind(4, r.params.dump()).bind(5, r.created).run();
  return r;
}

std::optional<JobRecord> JobStore::get(const std::string& id) {
  if (!valid_id(id)) return std::nullopt;
  std::lock_guard lock(mutex_);
  auto st = db_->prepare(std::string("SELECT ") + kColumns + " FROM jobs WHERE id = ?");
  st.bind(1, id);
  if (!st.step()) return std::nullopt;
  return read_row(st);
}

std::vector<JobRecord> JobStore::list(int limit) {
  std::lock_guard lock(mutex_);
  auto st = db_->prepare(std::string("SELECT ") + kColumns + " FROM jobs ORDER BY created DESC LIMIT ?");
  st.bind(1, limit);
  std::vector<JobRecord> out;
  while (st.step()) out.push_back(read_row(st));
  return out;
}

std::vector<JobRecord> JobStore::with_state(const std::string& state) {
  std::lock_guard lock(mutex_);
  auto st = db_->prepare(std::string("SELECT ") + kColumns + " FROM jobs WHERE state = ? ORDER BY created");
  st.bind(1, state);
  std::vector<JobRecord> out;
  while (st.step()) out.push_back(read_row(st));
  return out;
}

void JobStore::set_running(const std::string& id) {
  std::lock_guard lock(mutex_);
  db_->prepare("UPDATE jobs SET state='running', started=? WHERE id=?").bind(1, unix_now()).bind(2, id).run();
}

void JobStore::set_queued(const std::string& id) {
  std::lock_guard lock(mutex_);
  db_->prepare("UPDATE jobs SET state='queued', result=NULL, error='', progress='{}', started=0, finished=0 WHERE id=?")
      .bind(1, id).run();
}

void JobStore::set_progress(const std::string& id, const nlohmann::json& progress) {
  std::lock_guard lock(mutex_);
  db_->prepare("UPDATE jobs SET progress=? WHERE id=?").bind(1, progress.dump()).bind(2, id).run();
}

void JobStore::finish(const std::string& id, const std::string& state, const nlohmann::json& result,
                      const std::string& error) {
  std::lock_guard lock(mutex_);
  auto st = db_->prepare("UPDATE jobs SET state=?, result=?, error=?, finished=? WHERE id=?");
  st.bind(1, state);
  if (result.is_null()) st.bind_null(2);
  else st.bind(2, result.dump());
  st.bind(3, error).bind(4, unix_now()).bind(5, id).run();
}

namespace {

uint64_t tree_bytes(const fs::path& dir) {
  uint64_t n = 0;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, fs::directory_options::skip_permission_denied, ec), end; !ec && it != end;
       it.increment(ec)) {
    std::error_code e2;
    if (it->is_regular_file(e2)) n += it->file_size(e2);
  }
  return n;
}

}  // namespace

uint64_t JobStore::data_bytes(const fs::path& cache_dir) {
  return tree_bytes(data_ / "jobs") + (cache_dir.empty() ? 0 : tree_bytes(cache_dir));
}

PruneReport JobStore::prune(const Retention& retention, const fs::path& cache_dir,
                            const std::function<bool(const std::string&)>& busy) {
  std::lock_guard prune_lock(prune_mutex_);
  PruneReport report;
  std::vector<std::string> finished;  // oldest first
  {
    std::lock_guard lock(mutex_);
    auto st = db_->prepare("SELECT id, state FROM jobs ORDER BY CASE WHEN finished > 0 THEN finished ELSE created END, created");
    while (st.step()) {
      const std::string id = st.column_text(0), state = st.column_text(1);
      if (state != "queued" && state != "running") finished.push_back(id);
    }
  }
  // A folder without a row is left over from an interrupted prune (a job's row is always written
  // before its folder, and ids are never reused, so checking the row now is enough).
  auto has_row = [&](const std::string& id) {
    std::lock_guard lock(mutex_);
    auto st = db_->prepare("SELECT 1 FROM jobs WHERE id = ?");
    st.bind(1, id);
    return st.step();
  };
  std::error_code ec;
  std::map<std::string, uint64_t> job_bytes;
  uint64_t total = 0;
  for (const auto& e : fs::directory_iterator(data_ / "jobs", ec)) {
    const std::string id = e.path().filename().string();
    if (!valid_id(id)) continue;  // not ours
    if (!has_row(id)) {
      std::error_code e2;
      report.bytes_freed += tree_bytes(e.path());
      fs::remove_all(e.path(), e2);
      continue;
    }
    total += job_bytes[id] = tree_bytes(e.path());
  }
  struct CacheFile {
    fs::path path;
    uint64_t bytes;
    fs::file_time_type used;
  };
  std::vector<CacheFile> cache;
  if (!cache_dir.empty())
    for (const auto& e : fs::directory_iterator(cache_dir, ec)) {
      std::error_code e2;
      if (!e.is_regular_file(e2)) continue;
      cache.push_back({e.path(), e.file_size(e2), e.last_write_time(e2)});
      total += cache.back().bytes;
    }
  std::sort(cache.begin(), cache.end(), [](const CacheFile& a, const CacheFile& b) { return a.used < b.used; });

  // Deletes one finished job if it is still finished (checked under the connection's lock, so a
  // retry that queued it meanwhile wins) and not busy.
  auto remove_job = [&](const std::string& id) {
    if (busy && busy(id)) return false;
    {
      std::lock_guard lock(mutex_);
      auto st = db_->prepare("SELECT state FROM jobs WHERE id = ?");
      st.bind(1, id);
      if (!st.step()) return false;
      const std::string state = st.column_text(0);
      st.reset();
      if (state == "queued" || state == "running") return false;
      db_->prepare("DELETE FROM jobs WHERE id = ?").bind(1, id).run();
    }
    std::error_code e2;
    fs::remove_all(data_ / "jobs" / id, e2);
    const uint64_t b = job_bytes.count(id) ? job_bytes[id] : 0;
    total -= std::min(total, b);
    report.bytes_freed += b;
    ++report.jobs_deleted;
    return true;
  };
  size_t next = 0;  // the oldest finished job not yet considered
  int left = static_cast<int>(finished.size());
  if (retention.keep_jobs > 0) {
    while (left > retention.keep_jobs && next < finished.size()) {
      if (remove_job(finished[next])) --left;
      ++next;
    }
  }
  if (retention.max_bytes > 0) {
    for (size_t i = 0; total > retention.max_bytes && i < cache.size(); ++i) {
      std::error_code e2;
      if (fs::remove(cache[i].path, e2)) {
        total -= std::min(total, cache[i].bytes);
        report.bytes_freed += cache[i].bytes;
        ++report.cache_files_deleted;
      }
    }
    // Never the most recently finished job: what a user has just made stays downloadable.
    while (total > retention.max_bytes && next + 1 < finished.size()) {
      if (remove_job(finished[next])) --left;
      ++next;
    }
  }
  report.bytes = total;
  report.finished_jobs = left;
  return report;
}

fs::path JobStore::job_dir(const std::string& id) const {
  if (!valid_id(id)) throw Error("invalid job id", "job ids are 32 hex digits");
  const fs::path dir = data_ / "jobs" / id;
  std::error_code ec;
  fs::create_directories(dir, ec);
  return dir;
}

}  // namespace proctex::server
